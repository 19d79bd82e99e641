"""`python -m train.run --library sb3`: Stable-Baselines3 trains on the task's VectorEnv and the run
is recorded as the project's own: run.json, the database's statistics rows and events, TensorBoard
(RUN/tb), timed whole-state checkpoints and `--resume`, Ctrl-C / SIGTERM stopping after the current
step with a checkpoint and the policy, and policy/ (train.core.sb3_export) for train.evaluate,
studies, ONNX export and the dashboard.

    python -m train.run --library sb3 --task asc-inc-cog --algo sac --preset paper --seed 0

A checkpoint, RUN/checkpoints/<step>/, is SB3's own: model.zip (`model.save`: parameters and
optimizers), replay_buffer.pkl (`save_replay_buffer`, off-policy algorithms), and the curriculum
(and penalty normalizer) state; written into a temporary folder and renamed whole. A resumed run
loads the newest one that reads back whole (`Algo.load`, `load_replay_buffer`) and continues SB3's step count
(`reset_num_timesteps=False`); the robots start new episodes at the restored difficulty. Torch
runs on the CPU (SB3's advice for MLP policies; the GPU stays JAX's).
"""

from __future__ import annotations

import os
import shutil
import sys
import time

import numpy as np
from flax import serialization

from train.core.checkpoints import CheckpointError, checkpoint_dir, saved_steps, unreadable_warning
from train.core.plan import RunError, RunPlan
from train.core.sb3_env import TaskVecEnv, episode_metrics
from train.core.sb3_export import network_spec, policy_params
from train.core.sb3_presets import model_kwargs

MODEL, BUFFER, CURRICULUM = "model.zip", "replay_buffer.pkl", "curriculum.msgpack"


def _algo_class(algo: str):
  import stable_baselines3 as sb3  # noqa: PLC0415
  return {"sac": sb3.SAC, "td3": sb3.TD3, "ppo": sb3.PPO}[algo]


def _new_model(plan: RunPlan, venv: TaskVecEnv):
  """A fresh SB3 model of the plan's algorithm and preset."""
  kw = model_kwargs(plan.algo, plan.preset)
  if plan.algo == "td3":
    from stable_baselines3.common.noise import NormalActionNoise  # noqa: PLC0415
    a = venv.action_space.shape[0]
    kw["action_noise"] = NormalActionNoise(np.zeros(a), plan.preset.action_noise * np.ones(a))
  return _algo_class(plan.algo)("MlpPolicy", venv, policy_kwargs={"net_arch": list(plan.preset.hidden)},
                                seed=plan.seed, device="cpu", verbose=0, **kw)


class Checkpoints:
  """RUN/checkpoints/<step>/ of an SB3 run: save (atomic, the newest `keep` kept) and load."""

  def __init__(self, run_dir: str, keep: int):
    self.run_dir, self.dir, self.keep = run_dir, checkpoint_dir(run_dir), keep

  def save(self, model, venv: TaskVecEnv, step: int) -> str:
    tmp, final = os.path.join(self.dir, f".tmp-{step}"), os.path.join(self.dir, str(step))
    shutil.rmtree(tmp, ignore_errors=True)
    os.makedirs(tmp)
    model.save(os.path.join(tmp, MODEL))
    if hasattr(model, "replay_buffer"):
      model.save_replay_buffer(os.path.join(tmp, BUFFER))
    with open(os.path.join(tmp, CURRICULUM), "wb") as f:
      f.write(serialization.to_bytes(venv.curriculum_state()))
    shutil.rmtree(final, ignore_errors=True)
    os.replace(tmp, final)
    for old in self.steps()[:-self.keep]:
      shutil.rmtree(os.path.join(self.dir, str(old)), ignore_errors=True)
    return final

  def steps(self) -> list[int]:
    return saved_steps(self.run_dir)  # a step's folder is named by its number alone

  def load(self, plan: RunPlan, venv: TaskVecEnv, say=lambda m: print(m, file=sys.stderr)):
    """(model, step) of the newest checkpoint that reads back whole, with its replay buffer and
    curriculum restored; each damaged one newer than it is reported in one line and skipped (as
    RunCheckpoints.restore_latest_good does for the project's trainer)."""
    steps = self.steps()[::-1]
    for i, step in enumerate(steps):
      path = os.path.join(self.dir, str(step))
      try:
        model = load_model(plan.algo, path, venv)
        if os.path.exists(os.path.join(path, BUFFER)):
          model.load_replay_buffer(os.path.join(path, BUFFER))
        with open(os.path.join(path, CURRICULUM), "rb") as f:
          venv.set_curriculum_state(serialization.from_bytes(venv.curriculum_state(), f.read()))
        return model, step
      except Exception as e:  # zip, pickle and msgpack readers raise many types for damaged files
        say(unreadable_warning(self.dir, steps, i, e))
    raise CheckpointError(f"no readable checkpoint in {self.dir}")


def load_model(algo: str, checkpoint: str, venv: TaskVecEnv | None = None):
  """The SB3 model of a checkpoint folder (RUN/checkpoints/<step>), on the CPU; with venv, ready
  to train on it."""
  return _algo_class(algo).load(os.path.join(checkpoint, MODEL), env=venv, device="cpu")


def checkpoint_policy(run_dir: str, algo: str, step: int):
  """(network spec, (normalizer, policy) parameters) of the deterministic policy in an SB3 run's
  checkpoint at `step` (train.evaluate --checkpoint), as export() would write it."""
  model = load_model(algo, os.path.join(checkpoint_dir(run_dir), str(step)))
  spec = _spec(algo, model)
  return spec, policy_params(algo, model, spec)


def _spec(algo: str, model):
  """The NetworkSpec of a model's policy: its observation and action sizes, its MLP widths."""
  hidden = tuple(model.policy_kwargs["net_arch"])
  return network_spec(algo, model.observation_space.shape[0], model.action_space.shape[0], hidden)


def _callback(plan: RunPlan, venv: TaskVecEnv, reporter, ckpts: Checkpoints, db, stop, every_s: float):
  """SB3's callback: a report every training_metrics_steps, a timed checkpoint, and a stop request
  ending learn() after the current step."""
  from stable_baselines3.common.callbacks import BaseCallback  # noqa: PLC0415

  class Recorder(BaseCallback):
    def _on_training_start(self) -> None:
      self.next_report = self.num_timesteps + plan.preset.training_metrics_steps
      self.reported = self.num_timesteps
      self.streak, self.early = 0, False  # reports in a row meeting the early stop (train.core.early_stop)
      self.last_save, self.t0, self.t0_step = time.time(), time.time(), self.num_timesteps

    def _on_step(self) -> bool:
      if self.num_timesteps >= self.next_report:
        self.report()
      if every_s and time.time() - self.last_save >= every_s:
        ckpts.save(self.model, venv, self.num_timesteps)
        db.set_checkpoint(plan.run_id, ckpts.dir, self.num_timesteps)
        self.last_save = time.time()
      return stop.requested is None and not self.early

    def report(self) -> None:
      if self.num_timesteps == self.reported:
        return  # nothing new since the last report (the final call after learn())
      self.reported = self.num_timesteps
      sps = (self.num_timesteps - self.t0_step) / max(time.time() - self.t0, 1e-9)
      logged = {f"sb3/{k.replace('/', '_')}": float(v) for k, v in self.logger.name_to_value.items()
                if np.ndim(v) == 0}
      row = reporter(self.num_timesteps, {**episode_metrics(venv.take_finished()), **logged,
                                          "curriculum/eps": venv.eps, "training/steps_per_s": sps})
      if plan.early_stop is not None:
        self.streak = plan.early_stop.streak(self.streak, row)
        self.early = self.streak >= plan.early_stop.times
      self.next_report = self.num_timesteps + plan.preset.training_metrics_steps

  return Recorder()


def prepare(plan: RunPlan, keep: int):
  """(plan, train(db, stop, checkpoint_every_s) -> final figures): the env and the model built, or
  restored from the newest readable checkpoint before any record is touched (the plan then says
  the step it continues from, so the database drops only the rows past it)."""
  import dataclasses  # noqa: PLC0415
  venv = TaskVecEnv(plan.task, plan.num_envs, tuple(plan.preset.config_overrides) + plan.overrides, plan.seed)
  ckpts = Checkpoints(plan.out_dir, keep)
  try:
    model, step = ckpts.load(plan, venv) if plan.resume else (_new_model(plan, venv), 0)
  except CheckpointError as e:
    raise RunError(f"--resume {plan.out_dir}: {e}") from None
  if plan.resume:
    plan = dataclasses.replace(plan, start_step=step)
    print(f"resuming run {plan.run_id} from its checkpoint at step {step:,}, to {plan.total_steps:,} steps", flush=True)
  return plan, lambda db, stop, every_s: _learn(plan, venv, model, ckpts, db, stop, every_s)


def _learn(plan: RunPlan, venv: TaskVecEnv, model, ckpts: Checkpoints, db, stop, checkpoint_every_s: float) -> dict:
  """Trains the prepared model to the plan's total; checkpoints and exports where it stops; returns
  the run's final figures (step, reason, the last report's figures, policy)."""
  from train.core.progress import Reporter  # noqa: PLC0415
  step = plan.start_step
  reporter = Reporter(plan.total_steps, step, db, plan.run_id, os.path.join(plan.out_dir, "tb"),
                      wall_offset=db.wall_offset(plan.run_id, step))
  recorder = _callback(plan, venv, reporter, ckpts, db, stop, checkpoint_every_s)
  from stable_baselines3.common.logger import Logger  # noqa: PLC0415
  # SB3's own logger, without outputs: the recorder reads its values (otherwise learn() makes an
  # empty /tmp/SB3-<date> folder per call); the run's TensorBoard is the Reporter's
  model.set_logger(Logger(folder=None, output_formats=[]))
  try:
    model.learn(total_timesteps=plan.total_steps - step, callback=recorder, reset_num_timesteps=not plan.resume,
                progress_bar=False)
    recorder.report()
  finally:
    reporter.close()
  step = int(model.num_timesteps)
  ckpts.save(model, venv, step)
  db.set_checkpoint(plan.run_id, ckpts.dir, step)
  reason = "interrupted" if stop.requested is not None else "early_stop" if recorder.early else "done"
  return {"step": step, "reason": reason, "policy": export(plan, model, step), **reporter.latest}


def export(plan: RunPlan, model, step: int) -> str:
  """RUN/policy/ of the model's deterministic policy (train.core.sb3_export)."""
  from train.core.checkpoints import export_policy  # noqa: PLC0415
  spec = _spec(plan.algo, model)
  normalizer, policy = policy_params(plan.algo, model, spec)
  info = {"task": plan.task, "algo": plan.algo, "step": step, "run_id": plan.run_id, "config": plan.cfg.to_dict(),
          "trainer": "sb3"}
  return export_policy(plan.out_dir, normalizer, policy, spec, info)

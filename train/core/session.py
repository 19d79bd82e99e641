"""One training session of a run: build, start or restore the state, loop, then checkpoint and
export the policy of wherever it stopped (finished, early stop or interrupted)."""

from __future__ import annotations

import dataclasses
import os
import sys
from typing import Any

import jax

from train.core import ahead
from train.core.algos import ppo_split
from train.core.build import Training, build, compile_update, init_state, make_evaluator
from train.core.checkpoints import CHECKPOINT_EVERY_S, KEEP, CheckpointError, RunCheckpoints, checkpoint_dir, export_policy
from train.evaluation import milestone_folder
from train.core.loop import Checkpointer, Loop, LoopResult, Schedule, settle_all
from train.core.mesh import from_host, to_host
from train.core.plan import RunError, RunPlan
from train.core.probe import Probe
from train.core.progress import Reporter


@dataclasses.dataclass(frozen=True)
class SessionOptions:
  checkpoint_every_s: float = CHECKPOINT_EVERY_S
  keep_checkpoints: int = KEEP
  compile_ahead: str = ahead.DEFAULT  # the evaluations' programs compiled while the run trains: train.core.ahead
  split_update: str = ppo_split.DEFAULT  # PPO's update as programs compiled side by side: train.core.algos.ppo_split


@dataclasses.dataclass(frozen=True)
class Prepared:
  """A run ready to train: built, with its first state (fresh or restored)."""
  t: Training
  state: Any
  step: int


def prepare(plan: RunPlan, options: SessionOptions = SessionOptions()) -> Prepared:
  """Builds the run and makes or restores its state; raises RunError (nothing written) when no
  checkpoint of a resumed run is readable. The plan's start_step becomes the step restored."""
  t = build(plan)
  if t.note:
    print(f"note: {t.note}", flush=True)
  if not plan.resume:
    return Prepared(t, init_state(t, plan.seed), 0)
  state, step = _restore(t, RunCheckpoints(plan.out_dir, options.keep_checkpoints))
  print(f"resuming run {plan.run_id} from its checkpoint at step {step:,} ({checkpoint_dir(plan.out_dir)}/{step}), "
        f"to {plan.total_steps:,} steps", flush=True)
  return Prepared(dataclasses.replace(t, plan=dataclasses.replace(plan, start_step=step)), state, step)


def _restore(t: Training, ckpts: RunCheckpoints) -> tuple[Any, int]:
  """(state, step) of the newest readable checkpoint."""
  try:
    host, meta = ckpts.restore_latest_good(t.abstract)
  except CheckpointError as e:
    raise RunError(f"--resume {t.plan.out_dir}: {e}")
  return from_host(host, t.shardings), int(meta["step"])  # below the total: plan_run checked the newest


class BraxEvaluation(ahead.CompiledAhead):
  """evaluate(state) -> Brax's evaluation metrics (acting.Evaluator.run_evaluation) of the state's policy."""

  def __init__(self, t: Training, evaluator):
    self._params, self._evaluator = t.learner.policy_params, evaluator

  def __call__(self, state) -> dict:
    self.ready()
    return self._evaluator.run_evaluation(to_host(self._params(state)), training_metrics={})

  def ahead_job(self, state):
    return ahead.brax_evaluation_job(self._evaluator, to_host(self._params(state)))


def evaluator_of(t: Training, seed: int | None = None) -> BraxEvaluation | None:
  """evaluate(state) -> Brax evaluation metrics of a run of seed `seed` (default: the plan's), or None."""
  ev = make_evaluator(t, t.plan.seed if seed is None else seed)
  return None if ev is None else BraxEvaluation(t, ev)


def _loop(t: Training, db, stop, checkpointer: Checkpointer, state, start_step: int,
          options: SessionOptions) -> tuple[Loop, Reporter]:
  plan = t.plan
  evaluate, probe = evaluator_of(t), Probe(t) if plan.probe_every else None
  try:  # the evaluations trace once the update is lowered, and compile with it and while the run trains
    split = ppo_split.wanted(options.split_update, t.plan.algo, t.mesh.devices.size)
    if options.split_update == "on" and not split:
      print("note: --split-update on applies to PPO on one device; this run's update stays one program",
            flush=True)
    update, seconds = compile_update(t, meanwhile=lambda: ahead.start(options.compile_ahead, (evaluate, probe), state),
                                     split=split)
    db.compiled(plan.run_id, start_step, seconds)
    primary = jax.process_index() == 0  # under jax.distributed, process 0 reports
    reporter = Reporter(plan.total_steps, start_step, db, plan.run_id,
                        os.path.join(plan.out_dir, "tb") if primary else None,
                        stream=sys.stdout if primary else open(os.devnull, "w"),
                        wall_offset=db.wall_offset(plan.run_id, start_step))
    loop = Loop(update, t.learner.steps_per_update, checkpointer, reporter, stop, schedule_of(t, evaluate, probe))
    return loop, reporter
  except BaseException:  # no compilation thread left running at exit (train.core.ahead.settle)
    ahead.settle((evaluate, probe))
    raise


def schedule_of(t: Training, evaluate, probe) -> Schedule:
  """What happens between the run's updates: reports, Brax's evaluator (evaluate), the probe, milestones."""
  plan, p = t.plan, t.plan.preset
  eval_every = -(-plan.total_steps // max(p.num_evals - 1, 1))
  return Schedule(p.training_metrics_steps, plan.early_stop,
                  ((evaluate, eval_every), (probe, plan.probe_every)), plan.milestones,
                  lambda state, step, budget: _export(t, state, step, milestone_folder(budget)))


def checkpointer_of(t: Training, db, options: SessionOptions, last_step: int | None = None) -> Checkpointer:
  """The run's timed whole-state checkpoints, each recorded in the database."""
  plan = t.plan
  ckpts = RunCheckpoints(plan.out_dir, options.keep_checkpoints)
  meta = {"algo": plan.algo, "task": plan.task, "run_id": plan.run_id, "network": t.spec.to_json()}
  return Checkpointer(ckpts, meta, t.learner, lambda s: db.set_checkpoint(plan.run_id, ckpts.dir, s),
                      options.checkpoint_every_s, last_step=last_step)


def _export(t: Training, state, step: int, folder: str = "policy") -> str:
  """Exports the state's policy to RUN/<folder> (every process gathers, process 0 writes)."""
  normalizer, policy = to_host(t.learner.policy_params(state))
  plan = t.plan
  if jax.process_index() != 0:
    return os.path.join(plan.out_dir, folder)
  return export_policy(plan.out_dir, normalizer, policy, t.spec,
                       {"task": plan.task, "algo": plan.algo, "step": step, "run_id": plan.run_id,
                        "config": plan.cfg.to_dict()}, folder)


def finish_run(t: Training, result: LoopResult, checkpointer: Checkpointer, reporter: Reporter) -> dict[str, Any]:
  """Checkpoints the final state and exports its policy; returns the run's summary."""
  checkpointer.save(result.state, result.step)
  policy_dir = _export(t, result.state, result.step)
  return {"step": result.step, "reason": result.reason, "policy": policy_dir, **reporter.latest,
          **reporter.latest_probe}


def train(prepared: Prepared, db, stop, options: SessionOptions = SessionOptions()) -> dict[str, Any]:
  """Trains until the plan's total steps, an early stop or a stop request; returns the summary."""
  t, state, step = prepared.t, prepared.state, prepared.step
  checkpointer = checkpointer_of(t, db, options, last_step=step if t.plan.resume else None)
  loop, reporter = _loop(t, db, stop, checkpointer, state, step, options)
  try:
    return finish_run(t, loop.run(state, step, t.plan.total_steps), checkpointer, reporter)
  finally:
    settle_all([checkpointer])
    ahead.settle(f for f, _ in loop.schedule.evaluations)
    reporter.close()


def device_summary() -> str:
  """e.g. '2 x gpu, 2 processes'."""
  procs = f", {jax.process_count()} processes" if jax.process_count() > 1 else ""
  return f"{jax.device_count()} x {jax.default_backend()}{procs}"


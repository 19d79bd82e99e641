"""`python -m train.run --task TASK`: train a policy with Brax PPO or SAC on a task.

    python -m train.run --task asc-inc-cog                      # preset by backend: cpu | gpu
    python -m train.run --task des-inc-ang --algo sac --preset paper
    python -m train.run --task asc-inc-cog --set reward.cog_scale=0.5 --steps 5000000 --out runs/a
    python -m train.run --resume runs/a                         # continue a killed run

Writes into the run directory: run.json, checkpoints/ (orbax), policy/ (the exported policy),
tb/ (TensorBoard events); statistics and the run's status go to the experiment database.
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import json
import os
import secrets
import signal
import sys
from typing import Any

from mjx_tracks.envs.config import ConfigError, TaskConfig, from_dict, load_config
from train.db import ExperimentDB, default_path
from train.presets import PPOPreset, get_preset

EARLY_STOP_RETURN = {"up": 0.5, "down": 0.6}  # the paper's thresholds (mean return of recent episodes)


class RunError(Exception):
  """A bad request: reported as one line, nothing written."""


class EarlyStop(Exception):
  pass


@dataclasses.dataclass(frozen=True)
class RunPlan:
  run_id: str
  out_dir: str
  task: str
  algo: str
  preset_name: str
  preset: Any
  seed: int
  overrides: tuple[str, ...]
  cfg: TaskConfig
  total_steps: int
  num_envs: int
  resume: bool
  early_stop_return: float | None
  start_step: int = 0  # the checkpoint a resumed run continues from


def _default_preset() -> str:
  import jax  # noqa: PLC0415
  return "gpu" if jax.default_backend() in ("gpu", "cuda", "rocm", "tpu") else "cpu"


# options a resumed run takes from its run.json; giving one with --resume is refused
RESUME_FIXED = ("task", "algo", "preset", "num_envs", "seed", "set", "out", "early_stop", "early_stop_return")


def _plan_resume(args: argparse.Namespace) -> RunPlan:
  """The plan of a run to continue; refuses options that would change it, and finished runs."""
  given = [f"--{n.replace('_', '-')}" for n in RESUME_FIXED if getattr(args, n) not in (None, [], False)]
  if given:
    raise RunError(f"--resume continues a run with its own settings; drop {', '.join(given)} "
                   "(only --steps and --db may be given)")
  meta_path = os.path.join(args.resume, "run.json")
  if not os.path.exists(meta_path):
    raise RunError(f"--resume {args.resume}: no run.json there; not a run directory")
  try:
    with open(meta_path) as f:
      meta = json.load(f)
  except json.JSONDecodeError as e:
    raise RunError(f"--resume {args.resume}: run.json is corrupt ({e})")
  total = meta["total_steps"] if args.steps is None else args.steps
  from train.checkpoints import checkpoint_dir, saved_steps  # noqa: PLC0415  (orbax: only when resuming)
  steps = saved_steps(args.resume)
  if not steps:
    raise RunError(f"--resume {args.resume}: no checkpoint in {checkpoint_dir(args.resume)} to resume from")
  done = steps[-1]
  if done >= total:
    raise RunError(f"run {meta['run_id']} is finished ({done:,} of {meta['total_steps']:,} steps); to train "
                   f"it further: --resume {args.resume} --steps N with N > {done:,}")
  preset = dataclasses.replace(get_preset(meta["algo"], meta["preset"]), num_envs=meta["num_envs"])
  return RunPlan(meta["run_id"], os.path.abspath(args.resume), meta["task"], meta["algo"], meta["preset"],
                 preset, meta["seed"], tuple(meta["overrides"]), from_dict(meta["config"]), total,
                 meta["num_envs"], True, meta.get("early_stop_return"), done)


def new_run_id(task: str, algo: str, seed: int) -> str:
  """TASK-ALGO-sSEED-TIME-XXXX: the random suffix keeps runs started in the same second apart."""
  stamp = datetime.datetime.now().strftime("%Y%m%d-%H%M%S")
  return f"{task}-{algo}-s{seed}-{stamp}-{secrets.token_hex(2)}"


def plan_run(args: argparse.Namespace) -> RunPlan:
  """Resolves task, preset, config and run directory; raises RunError / ConfigError on bad input."""
  if args.resume:
    return _plan_resume(args)
  if not args.task:
    raise RunError("--task is required (or --resume DIR)")
  algo, seed = args.algo or "ppo", 0 if args.seed is None else args.seed
  preset_name = args.preset or _default_preset()
  try:
    preset = get_preset(algo, preset_name)
  except ValueError as e:
    raise RunError(str(e))
  overrides = tuple(preset.config_overrides) + tuple(args.set)
  cfg = load_config(args.task, overrides)
  num_envs = preset.num_envs if args.num_envs is None else args.num_envs
  if num_envs < 1:
    raise RunError("--num-envs must be >= 1")
  if isinstance(preset, PPOPreset) and (preset.batch_size * preset.num_minibatches) % num_envs:
    raise RunError(f"--num-envs {num_envs} must divide batch_size x num_minibatches = "
                   f"{preset.batch_size * preset.num_minibatches} of the {preset_name} PPO preset")
  steps = preset.num_timesteps if args.steps is None else args.steps
  if steps < 1:
    raise RunError("--steps must be >= 1")
  run_id = new_run_id(args.task, algo, seed)
  out_dir = os.path.abspath(args.out or os.path.join("runs", run_id))
  if os.path.exists(out_dir) and os.listdir(out_dir):
    other = os.path.join(out_dir, "run.json")
    what = f"run {json.load(open(other))['run_id']}" if os.path.exists(other) else "other files"
    raise RunError(f"{out_dir} already holds {what}; use --resume {out_dir} or another --out")
  early = None
  if args.early_stop or args.early_stop_return is not None:
    early = args.early_stop_return if args.early_stop_return is not None else \
        EARLY_STOP_RETURN.get(cfg.scene.direction if cfg.scene.kind == "stairs" else "", None)
    if early is None:
      raise RunError("--early-stop needs --early-stop-return for this task")
  return RunPlan(run_id, out_dir, args.task, algo, preset_name, preset, seed, tuple(args.set),
                 cfg, steps, num_envs, False, early)


def _write_run_json(plan: RunPlan) -> None:
  """run.json (atomically); a resumed run keeps its creation time."""
  os.makedirs(plan.out_dir, exist_ok=True)
  path = os.path.join(plan.out_dir, "run.json")
  now = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
  created = json.load(open(path)).get("created", now) if plan.resume and os.path.exists(path) else now
  meta = {"run_id": plan.run_id, "task": plan.task, "algo": plan.algo, "preset": plan.preset_name,
          "seed": plan.seed, "overrides": list(plan.overrides), "config": plan.cfg.to_dict(),
          "total_steps": plan.total_steps, "num_envs": plan.num_envs,
          "early_stop_return": plan.early_stop_return,
          "created": created}
  tmp = path + ".tmp"
  with open(tmp, "w") as f:
    json.dump(meta, f, indent=1)
  os.replace(tmp, path)


def train(plan: RunPlan, db: ExperimentDB) -> dict[str, Any]:
  """Runs the trainer; returns the final summary (step, last statistics, export path)."""
  import jax  # noqa: PLC0415

  from mjx_tracks.envs.task_env import TrackedRobotEnv  # noqa: PLC0415
  from mjx_tracks.envs.wrappers import global_stats_from_json, global_stats_to_json, wrap_for_training  # noqa: PLC0415
  from train import compat  # noqa: PLC0415
  from train.checkpoints import RunCheckpoints, export_policy, policy_params, restore_ppo_params  # noqa: PLC0415
  from train.networks import NetworkSpec  # noqa: PLC0415
  from train.progress import Reporter  # noqa: PLC0415

  compat.install()
  core = TrackedRobotEnv(plan.cfg)
  p = plan.preset
  hidden = (p.policy_hidden, p.value_hidden) if plan.algo == "ppo" else (p.hidden, p.hidden)
  spec = NetworkSpec(plan.algo, core.observation_size, core.action_size, *hidden)
  ckpts = RunCheckpoints(plan.out_dir)
  start_step, initial, raw = 0, None, None
  if plan.resume:
    if ckpts.latest_step() is None:
      raise RunError(f"--resume {plan.out_dir}: no checkpoint in {ckpts.dir} to resume from")
    try:
      raw, meta = ckpts.restore()
    except Exception as e:  # orbax raises several types for damaged files
      raise RunError(f"--resume {plan.out_dir}: checkpoint {ckpts.latest_step()} is unreadable ({e})")
    start_step = int(meta["step"])
    initial = global_stats_from_json(meta["global"]) if meta.get("global") else None
  remaining = plan.total_steps - start_step
  if remaining <= 0:
    raise RunError(f"{plan.run_id} already reached {start_step:,} of {plan.total_steps:,} steps")

  latest = {"global": initial}
  report = lambda g: latest.__setitem__("global", jax.tree_util.tree_map(lambda x: x, g))
  # evaluation during training: uniform scenes over the task's ranges, with its own curriculum
  eval_core = TrackedRobotEnv(dataclasses.replace(
      plan.cfg, scene=dataclasses.replace(plan.cfg.scene, sampler="uniform")))
  wrap_train = wrap_for_training(core, "i", initial=initial, report=report)
  wrap_eval = wrap_for_training(eval_core, "i")
  wrap = lambda env, **kw: (wrap_train if env is core else wrap_eval)(env, **kw)
  eps = lambda: float(latest["global"].curriculum.eps) if latest["global"] is not None else None
  reporter = Reporter(plan.total_steps, start_step, db, plan.run_id, os.path.join(plan.out_dir, "tb"), eps,
                      wall_offset=db.wall_offset(plan.run_id, start_step))
  meta_base = {"algo": plan.algo, "task": plan.task, "run_id": plan.run_id, "network": spec.to_json()}
  state = {"stop": False, "saved": None}

  def save(step: int, params) -> None:
    g = latest["global"]
    ckpts.save(step, params, {**meta_base, "global": global_stats_to_json(g) if g is not None else None})
    state["saved"] = step
    db.set_checkpoint(plan.run_id, ckpts.dir, step)

  def progress(step: int, metrics) -> None:
    row = reporter(start_step + step, metrics)
    if plan.early_stop_return is not None and "episode/sum_reward" in metrics and \
        row.get("return_mean", -1e9) >= plan.early_stop_return:
      state["stop"] = True
    if state["stop"] and state["saved"] == start_step + step:
      raise EarlyStop()

  stopped = False
  try:
    if plan.algo == "ppo":
      from brax.training.agents.ppo import train as ppo  # noqa: PLC0415
      _, params, _ = ppo.train(
          environment=core, eval_env=eval_core, wrap_env_fn=wrap, num_timesteps=remaining,
          episode_length=plan.cfg.episode.max_steps, num_envs=plan.num_envs,
          unroll_length=p.unroll_length, batch_size=p.batch_size, num_minibatches=p.num_minibatches,
          num_updates_per_batch=p.num_updates_per_batch, learning_rate=p.learning_rate,
          entropy_cost=p.entropy_cost, discounting=p.discounting, gae_lambda=p.gae_lambda,
          clipping_epsilon=p.clipping_epsilon, reward_scaling=p.reward_scaling,
          max_grad_norm=p.max_grad_norm, normalize_observations=True,
          network_factory=spec.factory(), num_evals=p.num_evals, num_eval_envs=p.num_eval_envs,
          log_training_metrics=True, training_metrics_steps=p.training_metrics_steps,
          run_evals=p.run_evals,
          progress_fn=progress, policy_params_fn=lambda s, _, prm: save(start_step + s, prm),
          restore_params=restore_ppo_params(raw, spec) if raw is not None else None,
          seed=plan.seed)
      save(start_step + remaining, params)
    else:
      from brax.training import checkpoint as brax_ckpt  # noqa: PLC0415
      from brax.training.agents.sac import train as sac  # noqa: PLC0415
      brax_dir = os.path.join(plan.out_dir, "brax_sac")
      restore_path = None
      if raw is not None:
        restore_path = meta.get("brax_checkpoint")
        if not restore_path or not os.path.exists(restore_path):
          raise RunError(f"--resume: SAC checkpoint {restore_path} is missing")

      def sac_progress(step, metrics):
        # brax saved this evaluation's parameters under brax_sac/<zero-padded step>/
        names = sorted(d for d in os.listdir(brax_dir) if d.isdigit()) if os.path.isdir(brax_dir) else []
        if names:
          meta_base["brax_checkpoint"] = os.path.join(brax_dir, names[-1])
          save(start_step + step, brax_ckpt.load(meta_base["brax_checkpoint"]))
        progress(step, metrics)

      _, params, _ = sac.train(
          environment=core, eval_env=eval_core, wrap_env_fn=wrap, num_timesteps=remaining,
          episode_length=plan.cfg.episode.max_steps, num_envs=plan.num_envs,
          batch_size=p.batch_size, learning_rate=p.learning_rate, discounting=p.discounting,
          tau=p.tau, reward_scaling=p.reward_scaling, grad_updates_per_step=p.grad_updates_per_step,
          min_replay_size=p.min_replay_size, max_replay_size=p.max_replay_size,
          normalize_observations=True, network_factory=spec.factory(), num_evals=p.num_evals,
          num_eval_envs=p.num_eval_envs, progress_fn=sac_progress, checkpoint_logdir=brax_dir,
          restore_checkpoint_path=restore_path, seed=plan.seed)
      save(start_step + remaining, params)
  except EarlyStop:
    stopped = True
  raw, meta = ckpts.restore()
  normalizer, policy = policy_params(raw, spec)
  policy_dir = export_policy(plan.out_dir, normalizer, policy, spec,
                             {"task": plan.task, "algo": plan.algo, "step": meta["step"],
                              "run_id": plan.run_id, "config": plan.cfg.to_dict()})
  reporter.close()
  return {"step": meta["step"], "stopped_early": stopped, "policy": policy_dir, **reporter.latest}


def _sigterm(*_):
  raise KeyboardInterrupt("SIGTERM")


def main(argv: list[str] | None = None) -> int:
  p = argparse.ArgumentParser(prog="python -m train.run", description=__doc__.splitlines()[0],
                              formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
  p.add_argument("--task", help="task name (configs/TASK.yaml)")
  p.add_argument("--algo", choices=("ppo", "sac"), help="default ppo")
  p.add_argument("--preset", help="cpu | gpu (| paper for sac); default from the JAX backend")
  p.add_argument("--num-envs", type=int, help="parallel environments (default: the preset's)")
  p.add_argument("--steps", type=int, help="total environment steps (default: the preset's)")
  p.add_argument("--seed", type=int, help="default 0")
  p.add_argument("--out", help="run directory (default runs/<run id>)")
  p.add_argument("--db", help="experiment database (default: experiments.sqlite beside the run directory)")
  p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                 help="dotted config override, e.g. --set reward.cog_scale=0.5")
  p.add_argument("--resume", metavar="DIR", help="continue the run in DIR from its last checkpoint")
  p.add_argument("--early-stop", action="store_true",
                 help="stop when the mean return of recent episodes reaches the task's threshold "
                      "(paper: 0.5 ascent, 0.6 descent)")
  p.add_argument("--early-stop-return", type=float, help="explicit early-stop threshold")
  args = p.parse_args(argv)
  try:
    plan = plan_run(args)
  except (RunError, ConfigError) as e:
    print(f"error: {e}", file=sys.stderr)
    return 2
  from mjx_tracks import compile_cache  # noqa: PLC0415
  compile_cache.enable()
  _write_run_json(plan)
  db = ExperimentDB(args.db or default_path(os.path.dirname(plan.out_dir)))
  db.start(plan.run_id, plan.task, plan.algo, plan.preset_name, plan.seed, plan.cfg.to_dict(),
           plan.out_dir, plan.total_steps, resume_step=plan.start_step if plan.resume else None)
  print(f"run {plan.run_id}: {plan.algo} ({plan.preset_name} preset), {plan.num_envs} envs, "
        f"{plan.total_steps:,} steps -> {plan.out_dir}", flush=True)
  signal.signal(signal.SIGTERM, _sigterm)
  status, final = "crashed", {}
  try:
    final = train(plan, db)
    status = "stopped_early" if final.get("stopped_early") else "done"
  except RunError as e:
    status = "failed"
    print(f"error: {e}", file=sys.stderr)
    return 2
  except KeyboardInterrupt:
    status = "killed"
    print("interrupted: the last checkpoint is kept; continue with --resume " + plan.out_dir, file=sys.stderr)
    return 130
  finally:
    db.finish(plan.run_id, status, final, final.get("step"), "early stop" if status == "stopped_early" else "")
  print(json.dumps({k: v for k, v in final.items()}, indent=1))
  return 0


if __name__ == "__main__":
  sys.exit(main())

"""speeds: what a task's hardest scene takes from a policy that ignores its observations: the
trials of `train.evaluate` (100 by default, starts varied by evaluation.trial_variation) at each
constant belt speed (m/s) with every joint held, optionally with one joint group's increments held
at +1 (e.g. --raise front: the front flippers driven to their upper limit and kept there). A trained
policy that ends where a constant mid-range speed does has learned neither the speed nor the joint
motion the scene needs (docs/results.md, "The paper's regime by both libraries")."""

from __future__ import annotations

import json

SPEEDS = (0.2, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0)  # m/s


def add_args(p) -> None:
  from train.evaluation import EVAL_TRIALS  # noqa: PLC0415
  p.add_argument("--tasks", default="asc-inc-cog", help="comma-separated")
  p.add_argument("--scene", default="hardest", help="an evaluation scene of train.evaluate")
  p.add_argument("--speeds", default=",".join(map(str, SPEEDS)), help="m/s, comma-separated, within the task's v_range")
  p.add_argument("--raise", dest="raised", default="", help="a joint action dimension held at +1 (e.g. front); none by default")
  p.add_argument("--trials", type=int, default=EVAL_TRIALS)


def constant_action(cfg, core, speed: float, raised: str):
  """The action vector: belt speed (m/s) as the controller encodes it, no turn, joints held (no
  increment; with absolute targets, at 0), but `raised`'s dimension at +1; BenchInputError for a speed out of range or an
  unknown dimension."""
  import jax.numpy as jnp  # noqa: PLC0415

  from train.bench.result import BenchInputError  # noqa: PLC0415
  lo, hi = cfg.control.v_range
  if not lo <= speed <= hi:
    raise BenchInputError(f"--speeds: {speed} m/s is outside the task's v_range [{lo}, {hi}]")
  held = jnp.zeros(core.sim.layout.n_joints)
  action = core.controller.encode(jnp.float32(speed), jnp.float32(0.0), held, held)
  if raised:
    dims = core.controller.dims
    if raised not in dims:
      raise BenchInputError(f"--raise: {raised!r} is not an action dimension of {cfg.control.mode}: {dims}")
    action = action.at[dims.index(raised)].set(1.0)
  return action


def rows_for(task: str, scene: str, speeds: list[float], raised: str, trials: int) -> list[dict]:
  import numpy as np  # noqa: PLC0415

  from mjx_tracks.baselines import constant_act  # noqa: PLC0415
  from mjx_tracks.envs.config import load_config  # noqa: PLC0415
  from mjx_tracks.envs.task_env import TrackedRobotEnv  # noqa: PLC0415
  from mjx_tracks.metrics import EPISODE_NAMES  # noqa: PLC0415
  from train.evaluation import EVAL_EPS, EVAL_SEED, scene_config, trial_runner  # noqa: PLC0415
  task_cfg = load_config(task)
  cfg = scene_config(task_cfg, scene)
  core = TrackedRobotEnv(cfg)
  actions = [constant_action(cfg, core, v, raised) for v in speeds]  # every input checked before compiling
  run = trial_runner(task_cfg, [scene], lambda action: constant_act(core, action), trials, EVAL_EPS, EVAL_SEED,
                     observe=lambda s: s)
  rows = []
  for speed, action in zip(speeds, actions):
    per_trial, _, _ = run(action, scene)
    rows.append({"task": task, "scene": scene, "speed": speed, "raised": raised or None, "trials": trials,
                 **{k: float(np.mean(per_trial[k])) for k in EPISODE_NAMES}})
    print(json.dumps(rows[-1]), flush=True)
  return rows


def run(args) -> tuple[list[dict], dict]:
  from train.bench.result import BenchInputError  # noqa: PLC0415
  try:
    speeds = [float(v) for v in args.speeds.split(",")]
  except ValueError as e:
    raise BenchInputError(f"--speeds: numbers in m/s, comma-separated, got {args.speeds!r}") from e
  rows = [r for task in args.tasks.split(",") for r in rows_for(task, args.scene, speeds, args.raised, args.trials)]
  return rows, {"trials": args.trials, "raised": args.raised or None}

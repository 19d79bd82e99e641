"""baselines: how far policies that ignore their observations get: the trials of `train.evaluate`
(each scene, 100 trials by default) with a constant action: 'zero' (half speed, joints held) and
'full' (full speed, joints held). A benchmark that such a policy solves measures little by
success alone; a trained policy should beat both on the task's own objective."""

from __future__ import annotations

import json

TASKS = ("asc-inc-cog", "asc-uni-cog", "des-inc-ang", "des-uni-ang")
SCENES = ("hardest", "uniform")
POLICIES = {"zero": 0.0, "full": 1.0}  # name -> the speed action (action 0); every other action 0


def add_args(p) -> None:
  from train.evaluation import EVAL_TRIALS  # noqa: PLC0415
  p.add_argument("--tasks", default=",".join(TASKS), help="comma-separated")
  p.add_argument("--scenes", default=",".join(SCENES), help="evaluation scenes, comma-separated")
  p.add_argument("--trials", type=int, default=EVAL_TRIALS)


def constant_act(action):
  """act for evaluation's trials, whose params are the constant action: every observation gets it."""
  import jax.numpy as jnp  # noqa: PLC0415
  return lambda obs: jnp.broadcast_to(action, (obs.shape[0], action.shape[0]))


def rows_for(task: str, scenes: list[str], trials: int) -> list[dict]:
  """One row per scene and constant policy: the mean of each per-trial figure (mjx_tracks.metrics)."""
  import jax.numpy as jnp  # noqa: PLC0415
  import numpy as np  # noqa: PLC0415

  from mjx_tracks.envs.config import load_config  # noqa: PLC0415
  from mjx_tracks.envs.task_env import TrackedRobotEnv  # noqa: PLC0415
  from mjx_tracks.metrics import EPISODE_NAMES  # noqa: PLC0415
  from train.evaluation import EVAL_EPS, EVAL_SEED, scene_config, trial_runner  # noqa: PLC0415
  rows = []
  for scene in scenes:
    cfg = scene_config(load_config(task), scene)
    size = TrackedRobotEnv(cfg).action_size
    run = trial_runner(cfg, constant_act, trials, EVAL_EPS, EVAL_SEED)
    for name, speed in POLICIES.items():
      per_trial, _, _ = run(jnp.zeros(size).at[0].set(speed))
      rows.append({"task": task, "scene": scene, "policy": name, "trials": trials,
                   **{k: float(np.mean(per_trial[k])) for k in EPISODE_NAMES}})
      print(json.dumps(rows[-1]), flush=True)
  return rows


def run(args) -> tuple[list[dict], dict]:
  rows = [r for task in args.tasks.split(",") for r in rows_for(task, args.scenes.split(","), args.trials)]
  return rows, {"trials": args.trials}

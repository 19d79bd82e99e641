"""baselines: how far policies that do not learn get: the trials of `train.evaluate` (each scene,
100 trials by default, starts varied by evaluation.trial_variation) with every baseline of
mjx_tracks.baselines that can drive the task (zero, full, random, scripted), compiled once per task
and scene (the baseline is picked by lax.switch on its index). A task whose constant baseline
succeeds on its hardest scene is saturated; a trained policy should beat every baseline on the
task's own objective."""

from __future__ import annotations

import json

TASKS = ("asc-inc-cog", "asc-uni-cog", "des-inc-ang", "des-uni-ang")
SCENES = ("hardest",)


def add_args(p) -> None:
  from train.evaluation import EVAL_TRIALS  # noqa: PLC0415
  p.add_argument("--tasks", default=",".join(TASKS), help="comma-separated")
  p.add_argument("--scenes", default=",".join(SCENES), help="evaluation scenes, comma-separated")
  p.add_argument("--trials", type=int, default=EVAL_TRIALS)


def switch_act(core, names: list[str]):
  """make_act for evaluation's trials whose params are a baseline's index in `names`."""
  import jax  # noqa: PLC0415

  from mjx_tracks.baselines import baseline  # noqa: PLC0415
  acts = [baseline(n).make(core) for n in names]
  return lambda index: (lambda states: jax.lax.switch(index, acts, states))


def rows_for(task: str, scenes: list[str], trials: int) -> list[dict]:
  """One row per scene and baseline: the mean of each per-trial figure (mjx_tracks.metrics)."""
  import jax.numpy as jnp  # noqa: PLC0415
  import numpy as np  # noqa: PLC0415

  from mjx_tracks.baselines import baselines_for, saturated  # noqa: PLC0415
  from mjx_tracks.envs.config import load_config  # noqa: PLC0415
  from mjx_tracks.envs.task_env import TrackedRobotEnv  # noqa: PLC0415
  from mjx_tracks.metrics import EPISODE_NAMES  # noqa: PLC0415
  from train.evaluation import EVAL_EPS, EVAL_SEED, trial_runner  # noqa: PLC0415
  rows = []
  task_cfg = load_config(task)
  names = baselines_for(task_cfg)
  run = trial_runner(task_cfg, scenes, switch_act(TrackedRobotEnv(task_cfg), names), trials, EVAL_EPS, EVAL_SEED,
                     observe=lambda s: s)  # one program for every scene of a stair task
  for scene in scenes:
    for i, name in enumerate(names):
      per_trial, _, _ = run(jnp.int32(i), scene)
      rows.append({"task": task, "scene": scene, "policy": name, "trials": trials,
                   **{k: float(np.mean(per_trial[k])) for k in EPISODE_NAMES}})
      print(json.dumps(rows[-1]), flush=True)
    if scene == "hardest":  # every row of the scene says whether a constant baseline saturates it
      verdict = saturated({r["policy"]: r["success"] for r in rows[-len(names):]})
      for r in rows[-len(names):]:
        r["saturated"] = verdict
  return rows


def run(args) -> tuple[list[dict], dict]:
  rows = [r for task in args.tasks.split(",") for r in rows_for(task, args.scenes.split(","), args.trials)]
  return rows, {"trials": args.trials}

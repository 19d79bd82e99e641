"""How far policies that ignore their observations get on the paper's four tasks: the trials of
`train.evaluate` (hardest and uniform scenes, 100 trials each) with a constant action: 'zero'
(half speed, joints held) and 'full' (full speed, joints held). A benchmark that such a policy
solves measures little by success alone. Prints a table; --out writes it as JSON.
Usage: cd scripts && python constant_baselines.py --out ../results/studies/constant_baselines.json"""

from __future__ import annotations

import argparse

import jax.numpy as jnp
import numpy as np

from mjx_tracks.envs.config import load_config
from mjx_tracks.envs.task_env import TrackedRobotEnv
from result_file import write_result
from train.evaluation import EVAL_EPS, EVAL_SEED, EVAL_TRIALS, scene_config, trial_runner

TASKS = ("asc-inc-cog", "asc-uni-cog", "des-inc-ang", "des-uni-ang")
SCENES = ("hardest", "uniform")
POLICIES = {"zero": 0.0, "full": None}  # name -> the speed action (None: +1), every other action 0


def constant_act(action: jnp.ndarray):
  """act for train.evaluate's trials, whose params are the constant action: every observation gets it."""
  return lambda obs: jnp.broadcast_to(action, (obs.shape[0], action.shape[0]))


def rows_for(task: str, trials: int) -> list[dict]:
  """One row per scene and constant policy: the mean of each per-trial figure."""
  rows = []
  for scene in SCENES:
    cfg = scene_config(load_config(task), scene)
    size = TrackedRobotEnv(cfg).action_size
    run = trial_runner(cfg, constant_act, trials, EVAL_EPS, EVAL_SEED)
    for name, speed in POLICIES.items():
      action = jnp.zeros(size).at[0].set(1.0 if speed is None else speed)  # action 0: forward speed
      per_trial, _, _ = run(action)
      rows.append({"task": task, "scene": scene, "policy": name, "trials": trials,
                   **{k: float(np.mean(v)) for k, v in per_trial.items() if k in
                      ("success", "progress", "pitch_rate", "tipped_over", "cog_deviation", "length")}})
      r = rows[-1]
      print(f"{task:12s} {scene:8s} {name:5s} success {r['success']:.2f} progress {r['progress']:.3f} "
            f"|pitch rate| {r['pitch_rate']:.3f} rad/s tip-overs {r['tipped_over']:.2f}", flush=True)
  return rows


def main() -> None:
  p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  p.add_argument("--trials", type=int, default=EVAL_TRIALS)
  p.add_argument("--tasks", default=",".join(TASKS))
  p.add_argument("--out")
  args = p.parse_args()
  rows = [r for task in args.tasks.split(",") for r in rows_for(task, args.trials)]
  write_result(args.out, rows, trials=args.trials)


if __name__ == "__main__":
  main()

"""`python -m train.onnx_drive FILE.onnx [--trials 20] [--scene hardest] [--compare RUN_DIR]`: an
exported policy drives the simulator as a robot's control loop would.

Every control step: the simulator's observation leaves as a numpy array, onnxruntime alone maps it
to an action (no JAX in the policy's loop), the action goes back to the simulator (the "robot",
stepped by JAX). The task and its config come from the file's metadata (train.export). With
--compare RUN_DIR, the same trials (same scenes, same starts) run again with the run's JAX policy
and both lines are printed: a closed-loop check of the export.
"""

from __future__ import annotations

import argparse
import os
import sys

import numpy as np


def drive(cfg, choose, trials: int, seed: int) -> dict:
  """Per-trial figures (train.evaluation.per_trial_figures) of `trials` episodes whose actions come
  from choose(observations (trials, n) numpy) -> actions (trials, k) numpy, one call per control step."""
  import jax  # noqa: PLC0415
  import jax.numpy as jnp  # noqa: PLC0415

  from mjx_tracks.envs.task_env import TrackedRobotEnv  # noqa: PLC0415
  from train.evaluation import EVAL_EPS, add_step, per_trial_figures, start_sums, trial_keys, trial_starts  # noqa: PLC0415
  core = TrackedRobotEnv(cfg)
  step, add = jax.jit(jax.vmap(core.step)), jax.jit(add_step)
  s = jax.jit(lambda keys: trial_starts(core, keys, EVAL_EPS))(trial_keys(trials, seed))
  acc, active = start_sums(s, trials), np.ones(trials, bool)
  for _ in range(cfg.episode.max_steps):
    action = np.asarray(choose(np.asarray(s.obs, np.float32)), np.float32)
    s = step(s, jnp.asarray(action))
    acc = add(acc, s, jnp.asarray(active))  # the trials the policy is still driving (the evaluator's sums)
    active &= np.asarray(s.done) == 0
    if not active.any():
      break
  return per_trial_figures(acc)


def onnx_chooser(path: str):
  """choose(observations) -> actions by onnxruntime (CPU), and the file's metadata."""
  from train.export import onnx_policy, read_metadata  # noqa: PLC0415
  return onnx_policy(path), read_metadata(path)


def main(argv: list[str] | None = None) -> int:
  p = argparse.ArgumentParser(prog="python -m train.onnx_drive", description=__doc__.splitlines()[0])
  p.add_argument("onnx", help="an ONNX policy written by python -m train.export")
  p.add_argument("--trials", type=int, default=20)
  p.add_argument("--scene", default="hardest", help="an evaluation scene of the task (train.evaluate --scene)")
  p.add_argument("--seed", type=int, default=1)
  p.add_argument("--compare", metavar="RUN_DIR", help="the same trials with this run's JAX policy")
  args = p.parse_args(argv)
  from mjx_tracks.limits import MAX_SEED, MAX_TRIALS  # noqa: PLC0415
  if not 1 <= args.trials <= MAX_TRIALS or not 0 <= args.seed <= MAX_SEED:
    print(f"error: --trials from 1 to {MAX_TRIALS:,}, --seed from 0 to {MAX_SEED}", file=sys.stderr)
    return 2
  from train.extras import require_extra  # noqa: PLC0415
  require_extra("export", "train.onnx_drive")
  from mjx_tracks.envs.config import ConfigError, from_dict  # noqa: PLC0415
  from train.evaluation import scene_config  # noqa: PLC0415
  try:
    choose, meta = onnx_chooser(args.onnx)
    if "config" not in meta:
      raise ValueError(f"{args.onnx} has no mjx_tracks metadata: write it with python -m train.export")
    cfg = scene_config(from_dict(meta["config"]), args.scene)
    runs = {"onnxruntime": choose}
    if args.compare:
      from train.core.policy import load_policy  # noqa: PLC0415
      runs["jax"] = load_policy(os.path.join(args.compare, "policy"))
  except (ConfigError, FileNotFoundError, ValueError) as e:
    print(f"error: {e}", file=sys.stderr)
    return 2
  except Exception as e:  # onnxruntime's own errors on a file that is not a model  # noqa: BLE001
    print(f"error: cannot load {args.onnx}: {str(e).splitlines()[0]}", file=sys.stderr)
    return 2
  for name, chooser in runs.items():
    f = drive(cfg, chooser, args.trials, args.seed)
    print(f"{meta['task']} {args.scene}, {name}: {args.trials} trials, success {f['success'].mean():.3f}, "
          f"progress {f['progress'].mean():.3f}, pitch rate {f['pitch_rate'].mean():.3f} rad/s, "
          f"length {f['length'].mean():.1f} steps", flush=True)
  return 0


if __name__ == "__main__":
  sys.exit(main())

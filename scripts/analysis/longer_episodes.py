"""Are a policy's failures under a robustness case stuck, or only slow? The run's exported policy on
one evaluation scene under one case of its robustness suite (evaluation.robustness), with the
episode's step limit as the task has it and longer: the same trials (scenes, starts and
perturbations drawn from the same keys) at each limit. A failure that a longer limit turns into a
success was slow; one that stays a failure is stuck (or tips over). Prints a table and writes JSON
with the device, command and date.

python scripts/analysis/longer_episodes.py RUN [--scene hardest] [--case friction-low] \
    [--factors 1,2,4] [--trials 100] --out FILE
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import sys

import jax
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
from mjx_tracks import atomic, compile_cache  # noqa: E402
from mjx_tracks.envs.config import apply_override, from_dict  # noqa: E402
from train.core.policy import act_from_params, load_policy_params  # noqa: E402
from train.core.run_record import run_config  # noqa: E402
from train.evaluation import EVAL_EPS, EVAL_SEED, ROBUST, trial_runner  # noqa: E402


def figures(task_cfg, policy, scene: str, case: str, max_steps: int, trials: int) -> dict:
  """Mean figures of `trials` trials of the policy (spec, params) on `scene` of task_cfg under
  `case`, episodes of at most max_steps control steps, and each trial's success (for pairing)."""
  cfg = from_dict(apply_override(task_cfg.to_dict(), f"episode.max_steps={max_steps}"))
  spec, params = policy
  case_scene = f"{scene}{ROBUST}{case}"  # the evaluation scene BASE+CASE (train.evaluation.scene_config)
  run = trial_runner(cfg, [case_scene], act_from_params(spec), trials, EVAL_EPS, EVAL_SEED)
  per_trial, _, _ = run(params, case_scene)
  mean = lambda k: round(float(np.mean(per_trial[k])), 3)  # noqa: E731
  return {"max_steps": max_steps, "seconds": max_steps * task_cfg.control.period, "success": mean("success"),
          "progress": mean("progress"), "tipped_over": mean("tipped_over"), "length": mean("length"),
          "per_trial_success": [int(x) for x in np.asarray(per_trial["success"]) > 0.5]}


def main(argv: list[str] | None = None) -> int:
  p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  p.add_argument("run_dir")
  p.add_argument("--scene", default="hardest")
  p.add_argument("--case", default="friction-low", help="a case of the run's evaluation.robustness")
  p.add_argument("--factors", default="1,2,4", help="episode step limits as multiples of the task's, comma-separated "
                 "(the first is the reference the others are paired with)")
  p.add_argument("--trials", type=int, default=100)
  p.add_argument("--out", required=True)
  args = p.parse_args(argv)
  compile_cache.enable()
  task_cfg = run_config(args.run_dir)
  policy = load_policy_params(os.path.join(args.run_dir, "policy"))
  rows = []
  for factor in map(float, args.factors.split(",")):
    n = int(round(factor * task_cfg.episode.max_steps))
    rows.append(figures(task_cfg, policy, args.scene, args.case, n, args.trials))
    print({k: v for k, v in rows[-1].items() if k != "per_trial_success"}, flush=True)
  first = np.asarray(rows[0]["per_trial_success"], bool)
  for r in rows[1:]:  # paired: the same trials at a longer limit
    r["rescued"] = int(np.sum(~first & np.asarray(r["per_trial_success"], bool)))
    r["lost"] = int(np.sum(first & ~np.asarray(r["per_trial_success"], bool)))
  atomic.write_json(args.out, {
      "device": str(jax.devices()[0]), "machine": platform.machine(), "run": os.path.abspath(args.run_dir),
      "command": "python scripts/analysis/longer_episodes.py " + " ".join(sys.argv[1:] if argv is None else argv),
      "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
      "scene": args.scene, "case": args.case, "trials": args.trials, "rows": rows})
  return 0


if __name__ == "__main__":
  sys.exit(main())

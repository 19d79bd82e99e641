"""Do policies fail on the same trials? For one evaluation scene (e.g. hardest+friction-low) and the
runs of a task across study databases: how many of the policies climb each trial, and whether that
count varies more than it would if a failure were independent of the trial. Every evaluation of a
scene draws the same trials (the same keys: train.evaluation.trial_keys), so trial t is the same
staircase, start and perturbation for every policy. If failures cluster on some trials (hard ones,
or impassable), the per-trial counts spread wider than the Poisson-binomial variance sum p_i (1 - p_i)
of policies succeeding independently with their own rates p_i; if they do not, no trial is harder than
another and each failure is the rollout's chance.

python scripts/analysis/shared_failures.py results/studies/robust*/study.sqlite \
    --scene hardest+friction-low --task asc-inc-cog --out results/sim-to-real/shared-failures.json
"""

from __future__ import annotations

import argparse
import datetime
import json
import sys

import numpy as np

from train.db import read_only


def successes(dbs: list[str], scene: str, task: str) -> dict[str, dict[int, float]]:
  """{db:run_id: {trial: success}} of the trained runs (not baselines) of task (its name or a
  variant's: task-...) evaluated on scene."""
  out: dict[str, dict[int, float]] = {}
  for db in dbs:
    with read_only(db) as c:
      rows = c.execute("SELECT e.run_id, e.trial, e.success FROM evals e JOIN experiments x USING (run_id) "
                       "WHERE e.scene = ? AND (x.task = ? OR x.task LIKE ?) AND x.algo != 'baseline'",
                       (scene, task, f"{task}-%")).fetchall()
    for run, trial, ok in rows:
      out.setdefault(f"{db}:{run}", {})[trial] = ok
  return out


def summary(table: dict[str, dict[int, float]]) -> dict:
  """Per-trial counts of succeeding policies against the trial-independent expectation."""
  runs = sorted(table)
  trials = sorted(set.intersection(*(set(t) for t in table.values())))
  m = np.array([[table[r][t] for t in trials] for r in runs])  # (policies, trials) 0 / 1
  p, counts = m.mean(axis=1), m.sum(axis=0)
  return {"policies": len(runs), "trials": len(trials), "success_per_policy": dict(zip(runs, p.round(3).tolist())),
          "mean_success": float(p.mean()),
          "trials_climbed_by_none": int((counts == 0).sum()),
          "policies_climbing_a_trial_histogram": np.bincount(counts.astype(int), minlength=len(runs) + 1).tolist(),
          "count_variance_observed": float(counts.var()),
          "count_variance_if_trial_independent": float((p * (1 - p)).sum())}


def main(argv=None) -> int:
  p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  p.add_argument("dbs", nargs="+", help="study databases (STUDY/study.sqlite)")
  p.add_argument("--scene", default="hardest+friction-low")
  p.add_argument("--task", default="asc-inc-cog", help="the task, its variants (TASK-...) included")
  p.add_argument("--out", help="write the summary here as JSON (with the command and date)")
  args = p.parse_args(argv)
  table = successes(args.dbs, args.scene, args.task)
  if not table:
    print(f"error: no run of {args.task} evaluated on {args.scene} in {args.dbs}", file=sys.stderr)
    return 2
  result = {"command": "python " + " ".join(sys.argv), "date": datetime.date.today().isoformat(),
            "scene": args.scene, "task": args.task, **summary(table)}
  print(json.dumps({k: v for k, v in result.items() if k != "success_per_policy"}, indent=1))
  if args.out:
    with open(args.out, "w") as f:
      json.dump(result, f, indent=1)
  return 0


if __name__ == "__main__":
  sys.exit(main())

"""Do policies fail on the same trials? For one evaluation scene (e.g. hardest+friction-low) and the
runs of a task across study databases: how many of the policies have the outcome (--outcome: success,
or collided) in each trial, and whether that count varies more than it would if the outcome were
independent of the trial. Every evaluation of a scene draws the same trials (the same keys:
train.evaluation.trial_keys), so trial t is the same staircase or layout, start and perturbation for
every policy whose task config has the same `scene` section: runs are compared within such families
only (a family per distinct scene config, each config read with today's defaults for keys it
predates). If outcomes cluster on some trials (hard ones, or impassable), the per-trial counts spread
wider than the Poisson-binomial variance sum p_i (1 - p_i) of policies with their own rates p_i
acting independently of the trial; if they do not, no trial is harder than another and each
outcome is the rollout's chance.

python scripts/analysis/shared_failures.py results/studies/robust*/study.sqlite \
    --scene hardest+friction-low --task asc-inc-cog --out results/sim-to-real/shared-failures.json
python scripts/analysis/shared_failures.py results/studies/nav/study.sqlite --scene nav/zigzag \
    --task nav-obstacles --outcome collided --out results/nav/shared-collisions-zigzag.json
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import sys

import numpy as np

from mjx_tracks import atomic
from train.db import read_only
from provenance import provenance  # scripts/analysis/provenance.py (this script's folder is on sys.path)

OUTCOMES = ("success", "collided")  # evals columns a trial's 0 / 1 outcome is read from


def scene_family(config_json: str) -> str:
  """The run's `scene` config as canonical JSON, validated and with today's defaults filled in:
  runs with the same family draw the same scene for the same trial."""
  from mjx_tracks.envs.config import from_dict  # noqa: PLC0415
  return json.dumps(dataclasses.asdict(from_dict(json.loads(config_json)).scene), sort_keys=True)


def outcomes(dbs: list[str], scene: str, task: str, outcome: str = "success") -> dict[str, dict[str, dict[int, float]]]:
  """{scene family: {db:run_id: {trial: outcome}}} of the trained runs (not baselines) of task (its
  name or a variant's: task-...) evaluated on scene."""
  if outcome not in OUTCOMES:
    raise ValueError(f"outcome {outcome!r}: one of {', '.join(OUTCOMES)}")
  out: dict[str, dict[str, dict[int, float]]] = {}
  for db in dbs:
    if not os.path.isfile(db):
      raise FileNotFoundError(f"{db}: no such study database")
    with read_only(db) as c:
      rows = c.execute(f"SELECT e.run_id, e.trial, e.{outcome}, x.config_json FROM evals e "  # noqa: S608
                       "JOIN experiments x USING (run_id) "
                       "WHERE e.scene = ? AND (x.task = ? OR x.task LIKE ?) AND x.algo != 'baseline'",
                       (scene, task, f"{task}-%")).fetchall()
    families: dict[str, str] = {}  # config_json -> family, each parsed once
    for run, trial, value, config_json in rows:
      family = families.setdefault(config_json, scene_family(config_json))
      out.setdefault(family, {}).setdefault(f"{db}:{run}", {})[trial] = value
  return out


def shared_trials(table: dict[str, dict[int, float]]) -> list[int]:
  """The trials every run of the table ran, in order."""
  return sorted(set.intersection(*(set(t) for t in table.values())))


def summary(table: dict[str, dict[int, float]]) -> dict:
  """Per-trial counts of the policies with the outcome against the trial-independent expectation,
  over the trials every policy ran (how many others there were is counted)."""
  runs, trials = sorted(table), shared_trials(table)
  m = np.array([[table[r][t] for t in trials] for r in runs])  # (policies, trials) 0 / 1
  p, counts = m.mean(axis=1), m.sum(axis=0)
  every = set.union(*(set(t) for t in table.values()))
  return {"policies": len(runs), "trials": len(trials), "trials_not_every_policy_ran": len(every) - len(trials),
          "rate_per_policy": dict(zip(runs, p.round(3).tolist())),
          "mean_rate": float(p.mean()),
          "trials_of_no_policy": int((counts == 0).sum()),
          "trials_of_every_policy": int((counts == len(runs)).sum()),
          "policies_per_trial_histogram": np.bincount(counts.astype(int), minlength=len(runs) + 1).tolist(),
          "count_variance_observed": float(counts.var()),
          "count_variance_if_trial_independent": float((p * (1 - p)).sum())}


def main(argv=None) -> int:
  p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  p.add_argument("dbs", nargs="+", help="study databases (STUDY/study.sqlite)")
  p.add_argument("--scene", default="hardest+friction-low")
  p.add_argument("--task", default="asc-inc-cog", help="the task, its variants (TASK-...) included")
  p.add_argument("--outcome", default="success", choices=OUTCOMES, help="the trial outcome counted")
  p.add_argument("--out", help="write the summary here as JSON (with the device, command and date)")
  args = p.parse_args(argv)
  try:
    tables = outcomes(args.dbs, args.scene, args.task, args.outcome)
  except FileNotFoundError as e:
    print(f"error: {e}", file=sys.stderr)
    return 2
  if not tables:
    print(f"error: no run of {args.task} evaluated on {args.scene} in {args.dbs}", file=sys.stderr)
    return 2
  families = sorted(({"scene_config": json.loads(f), **summary(t)} for f, t in tables.items()),
                    key=lambda r: -r["policies"])
  result = {**provenance(), "scene": args.scene, "task": args.task, "outcome": args.outcome, "families": families}
  for r in families:
    print(json.dumps({k: v for k, v in r.items() if k not in ("rate_per_policy", "scene_config")}))
  if args.out:
    atomic.write_json(args.out, result)
  return 0


if __name__ == "__main__":
  sys.exit(main())

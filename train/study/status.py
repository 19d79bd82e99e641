"""`python -m train.study status NAME [--root studies] [--runs]`: where a study stands, from its
folder alone (state.json, the run folders): runs done / failed / not finished, attempts, and per
run (--runs) its status, attempts, last worker and hardest-staircase success."""

from __future__ import annotations

import argparse
import json
import os
import sys

from train.core.run_record import run_id_in
from train.db import read_only
from train.study.executor import STUDY_DB, cell_folder_of, folder_parser, no_study, overview, read_cells


# state.json's "running" means handed to the cluster: running, or waiting there for a slot (the
# folder alone cannot tell which; the study's own progress lines ask the scheduler)
SHOWN = {"running": "submitted", "queued": "to retry"}


def _database_successes(folder: str) -> dict[str, float]:
  """{run_id: mean success} of each run's final hardest-scene evaluation in the study's database (a
  milestone's trials carry its budget and are left out): one read for every line of `--runs`."""
  db = os.path.join(folder, STUDY_DB)
  if not os.path.exists(db):
    return {}
  with read_only(db) as c:
    return dict(c.execute("SELECT run_id, avg(success) FROM evals WHERE scene = 'hardest' AND budget IS NULL "
                          "GROUP BY run_id"))


def _success(run_folder: str, in_database: dict[str, float]) -> str:
  """The run's success on the hardest scene: its report (eval-hardest.json, in a study under way), else
  the mean of that evaluation's trials in the study's database (a committed study keeps no per-run
  reports: results/studies/README.md)."""
  path = os.path.join(run_folder, "eval-hardest.json")
  if os.path.exists(path):
    return f"{json.load(open(path))['metrics']['success']['mean']:.2f}"
  mean = in_database.get(run_id_in(run_folder))
  return "-" if mean is None else f"{mean:.2f}"


def summary(folder: str, runs: bool = False) -> list[str]:
  """The lines `status` prints; FileNotFoundError if the folder holds no study."""
  state = read_cells(folder)
  retried = sum(1 for c in state.values() if len(c["attempts"]) > 1)
  lines = [f"study {os.path.basename(folder)}: {overview(state)}, {retried} runs retried"]
  if runs:
    lines.append(f"{'run':<44} {'status':<10} {'attempts':>8}  {'last worker':<12} success (hardest)")
    in_database = _database_successes(folder)
    for cid, c in state.items():
      last = c["attempts"][-1] if c["attempts"] else {}
      shown = SHOWN.get(c["status"], c["status"])
      lines.append(f"{cid:<44} {shown:<10} {len(c['attempts']):>8}  {str(last.get('worker') or '-'):<12} "
                   f"{_success(cell_folder_of(folder, cid), in_database)}")
  return lines


def main(argv: list[str]) -> int:
  p = folder_parser("status", __doc__)
  p.add_argument("--runs", action="store_true", help="one line per run")
  args = p.parse_args(argv)
  folder = os.path.join(args.root, args.name)
  try:
    print("\n".join(summary(folder, args.runs)))
  except FileNotFoundError as e:
    return no_study(folder, args.name, e.filename)
  return 0

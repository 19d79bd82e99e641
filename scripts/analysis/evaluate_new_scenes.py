"""Evaluates a study's finished runs on the scenes of their evaluation suite that they lack (a suite
that grew after they ran, e.g. held-out terrains), recording every trial in the study's database.

python scripts/analysis/evaluate_new_scenes.py results/studies/terrain [--trials 100] [--tasks T ...]
"""

from __future__ import annotations

import argparse
import os
import sys

from train import evaluate, evaluation
from train.core.run_record import run_config
from train.study.executor import STUDY_DB, read_cells, cell_folder_of


def missing_scenes(run_dir: str, cfg) -> list[str]:
  """Suite scenes of the run's task config (today's suite) without an eval-<scene>.json in its folder."""
  return [s for s in evaluation.suite_scenes(cfg) if not os.path.exists(evaluation.report_path(run_dir, s, None))]


def main(argv: list[str] | None = None) -> int:
  p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  p.add_argument("study_folder")
  p.add_argument("--trials", type=int, default=evaluation.EVAL_TRIALS)
  p.add_argument("--tasks", nargs="*", help="only the runs of these tasks")
  args = p.parse_args(argv)
  db = os.path.join(args.study_folder, STUDY_DB)
  for cid, cell in read_cells(args.study_folder).items():
    run = cell_folder_of(args.study_folder, cid)
    if cell["status"] != "done" or not os.path.isdir(os.path.join(run, "policy")):
      continue
    cfg = run_config(run)
    if args.tasks and cfg.task not in args.tasks:
      continue
    for scene in missing_scenes(run, cfg):
      print(f"[{cid}] {scene}", flush=True)
      if evaluate.main([run, "--scene", scene, "--trials", str(args.trials), "--db", db]) != 0:
        return 2
  return 0


if __name__ == "__main__":
  sys.exit(main())

"""`python -m train.study status NAME [--root studies] [--runs]`: where a study stands, from its
folder alone (state.json, the run folders): runs done / failed / not finished, attempts, and per
run (--runs) its status, attempts, last worker and hardest-staircase success."""

from __future__ import annotations

import argparse
import json
import os
import sys

from train.study.executor import cell_folder_of, overview, read_cells


# state.json's "running" means handed to the cluster: running, or waiting there for a slot (the
# folder alone cannot tell which; the study's own progress lines ask the scheduler)
SHOWN = {"running": "submitted", "queued": "to retry"}


def _success(run_folder: str) -> str:
  path = os.path.join(run_folder, "eval-hardest.json")
  if not os.path.exists(path):
    return "-"
  return f"{json.load(open(path))['metrics']['success']['mean']:.2f}"


def summary(folder: str, runs: bool = False) -> list[str]:
  """The lines `status` prints; FileNotFoundError if the folder holds no study."""
  state = read_cells(folder)
  retried = sum(1 for c in state.values() if len(c["attempts"]) > 1)
  lines = [f"study {os.path.basename(folder)}: {overview(state)}, {retried} runs retried"]
  if runs:
    lines.append(f"{'run':<44} {'status':<10} {'attempts':>8}  {'last worker':<12} success (hardest)")
    for cid, c in state.items():
      last = c["attempts"][-1] if c["attempts"] else {}
      shown = SHOWN.get(c["status"], c["status"])
      lines.append(f"{cid:<44} {shown:<10} {len(c['attempts']):>8}  {str(last.get('worker') or '-'):<12} "
                   f"{_success(cell_folder_of(folder, cid))}")
  return lines


def main(argv: list[str]) -> int:
  p = argparse.ArgumentParser(prog="python -m train.study status", description=__doc__.splitlines()[0])
  p.add_argument("name", help="the study's name (its folder under --root)")
  p.add_argument("--root", default="studies")
  p.add_argument("--runs", action="store_true", help="one line per run")
  args = p.parse_args(argv)
  folder = os.path.join(args.root, args.name)
  try:
    print("\n".join(summary(folder, args.runs)))
  except FileNotFoundError:
    print(f"error: no study in {folder} (no state.json); start it with python -m train.study {args.name}",
          file=sys.stderr)
    return 2
  return 0

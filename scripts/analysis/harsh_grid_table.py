"""The table of a harsh-grid evaluation (scripts/gpu/harsh_grid.sh): for every task and kind of
policy (trained runs grouped by task, or a baseline), success on each case: IQM over the runs
(seeds) with its 95 % bootstrap interval (train.study.statistics, as the study report), the runs'
range, and the trials each run had. Reads every DIR/*/eval-hardest+CASE.json.

    python scripts/analysis/harsh_grid_table.py /tmp/harsh [--json results/sim-to-real/harsh-grid.json]
"""

from __future__ import annotations

import argparse
import collections
import datetime
import glob
import json
import os
import shlex
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, ROOT)
PREFIX = "eval-hardest+"


def read_reports(folder: str) -> dict[tuple[str, str, str], list[dict]]:
  """{(task, policy kind, case): [report, ...]}: a trained run's kind is ALGO/PRESET, a baseline's
  `baseline-NAME` (its run record's preset is the baseline's name); one report per run folder and case."""
  from train.core.run_record import read_run_record  # noqa: PLC0415
  out = collections.defaultdict(list)
  for path in sorted(glob.glob(os.path.join(folder, "*", PREFIX + "*.json"))):
    r = json.load(open(path))
    preset = read_run_record(os.path.dirname(path))["preset"]
    kind = f"baseline-{preset}" if r["algo"] == "baseline" else f"{r['algo']}/{preset}"
    out[(r["task"], kind, r["scene"][len("hardest+"):])].append(r)
  if not out:
    raise ValueError(f"no {PREFIX}CASE.json reports in the folders of {folder}")
  return out


def table(reports: dict[tuple[str, str, str], list[dict]]) -> list[dict]:
  """One row per (task, kind, case): runs, trials per run, IQM success [low, high], min and max."""
  from train.study.statistics import iqm_intervals  # noqa: PLC0415
  rows = []
  for (task, kind, case), rs in sorted(reports.items()):
    success = [r["metrics"]["success"]["mean"] for r in rs]
    (iqm, low, high), = iqm_intervals({"x": success}).values()
    rows.append({"task": task, "policy": kind, "case": case, "runs": len(rs), "trials": sorted({r["trials"] for r in rs}),
                 "success_iqm": round(iqm, 3), "ci95": [round(low, 3), round(high, 3)],
                 "success_min": min(success), "success_max": max(success),
                 "device": sorted({r["device"] for r in rs})})
  return rows


def markdown(rows: list[dict]) -> str:
  lines = ["| task | policy | case | runs | success IQM [95 % CI] | runs' range |", "|---|---|---|---|---|---|"]
  for r in rows:
    lines.append(f"| {r['task']} | {r['policy']} | {r['case']} | {r['runs']} | {r['success_iqm']:.2f} "
                 f"[{r['ci95'][0]:.2f}, {r['ci95'][1]:.2f}] | {r['success_min']:.2f} - {r['success_max']:.2f} |")
  return "\n".join(lines)


def main(argv=None) -> int:
  p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
  p.add_argument("folder", help="the harsh-grid folder (its run and baseline folders)")
  p.add_argument("--json", help="also write the rows, with the command, to this file")
  p.add_argument("--made-by", default="", help="with --json: the command that made the folder, recorded beside the rows")
  args = p.parse_args(argv)
  try:
    rows = table(read_reports(args.folder))
  except ValueError as e:
    print(f"error: {e}", file=sys.stderr)
    return 2
  print(markdown(rows))
  if args.json:
    with open(args.json, "w") as f:
      given = [a for a in (argv or sys.argv[1:]) if a != args.made_by and a != "--made-by"]
      json.dump({"command": "python scripts/analysis/harsh_grid_table.py " + shlex.join(given),
                 "made_by": args.made_by, "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
                 "rows": rows}, f, indent=1)
  return 0


if __name__ == "__main__":
  sys.exit(main())

"""One small table of a few runs' evaluation reports, for results/ (which keeps summaries, not run
folders): for each run folder, its path (from the summary's folder) and record (run id, task,
algorithm, preset, seed, steps) and, for each `eval-*.json` report in it, the scene (SCENE@BUDGET for a
milestone's policy; a second report of a scene as SCENE (N trials) when it has fewer trials, else
SCENE (its file)), the report's file, the number of trials, the report's command, device and date,
and the mean of each figure (success, progress, tip-overs, pitch rate, ...). The reports' own
figures, unchanged; the per-trial rows stay in the reports (re-made by their commands).

    python scripts/analysis/eval_summary.py RUN [RUN ...] --out FILE.json
"""

from __future__ import annotations

import argparse
import glob
import json
import os
import shlex
import sys

RECORD_KEYS = ("run_id", "task", "algo", "preset", "seed", "total_steps")  # total_steps: the steps asked
REPORT_KEYS = ("trials", "command", "device", "date")


def run_summary(run_dir: str, base: str = ".") -> dict:
  """The run's record and the means of each of its evaluation reports, by scene; the folder named
  relative to `base` (the summary's folder)."""
  with open(os.path.join(run_dir, "run.json")) as f:
    record = json.load(f)
  reports = []
  for path in sorted(glob.glob(os.path.join(run_dir, "eval-*.json"))):
    with open(path) as f:
      report = json.load(f)
    at = f"@{report['budget']}" if report.get("budget") is not None else ""  # a milestone's policy
    reports.append((report["scene"] + at, -report["trials"], path, report))
  scenes = {}
  for key, _, path, report in sorted(reports):  # of one scene, the report with the most trials first
    if key in scenes:  # e.g. eval-hardest.10-trials.json beside eval-hardest.json: both kept
      fewer = report["trials"] < scenes[key]["trials"]
      key += f" ({report['trials']} trials)" if fewer else f" ({os.path.basename(path)})"
    if key in scenes:
      raise ValueError(f"{path}: a second report of {key} in {run_dir}")
    scenes[key] = {"file": os.path.basename(path), **{k: report.get(k) for k in REPORT_KEYS},
                   **{name: m["mean"] for name, m in report["metrics"].items()}}
  if not scenes:
    raise ValueError(f"{run_dir}: no eval-*.json report (python -m train.evaluate RUN --suite makes them)")
  return {"folder": os.path.relpath(run_dir, base), **{k: record.get(k) for k in RECORD_KEYS},
          "scenes": scenes}


def main(argv=None) -> int:
  p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  p.add_argument("runs", nargs="+", help="run folders")
  p.add_argument("--out", required=True, help="the summary (JSON)")
  args = p.parse_args(argv)
  try:
    runs = [run_summary(r, os.path.dirname(os.path.abspath(args.out))) for r in args.runs]
    made_by = shlex.join(["python", "scripts/analysis/eval_summary.py", *args.runs, "--out", args.out])
    with open(args.out, "w") as f:
      json.dump({"made_by": made_by, "runs": runs}, f, indent=1)
  except (OSError, ValueError, KeyError, TypeError) as e:
    print(f"error: {e}", file=sys.stderr)
    return 2
  print(f"wrote {args.out}: {len(runs)} runs, {sum(len(r['scenes']) for r in runs)} reports")
  return 0


if __name__ == "__main__":
  sys.exit(main())

"""Time-to-solve table from gpu_time_to_solve.sh's logs and evaluations: per seed the process wall
time to the exported policy, the step it stopped at, why, and its success on the hardest
staircase (100 trials); the median over seeds of the solved ones.

    python scripts/summarize_time_to_solve.py results/time-to-solve
"""

from __future__ import annotations

import glob
import json
import os
import re
import statistics
import sys

from results_table import log_header, write_summary
from train.early_stop import EARLY_STOP_SUCCESS


def seed_row(log_path: str) -> dict:
  log = open(log_path).read()
  eval_path = log_path.replace("_train.log", "_eval_hardest.json")
  final = re.search(r'"step": (\d+),\s*"reason": "(\w+)"', log)
  wall = re.search(r"process wall_s ([\d.]+)", log)
  compiled = re.search(r"compiled in ([\d,]+) s", log)
  success = json.load(open(eval_path))["metrics"]["success"]["mean"] if os.path.exists(eval_path) else None
  return {"step": int(final.group(1)) if final else None, "reason": final.group(2) if final else "failed",
          "process_wall_s": float(wall.group(1)) if wall else None,
          "compile_s": float(compiled.group(1).replace(",", "")) if compiled else None,
          "hardest_success": success}


def main(folder: str) -> None:
  rows = {int(re.search(r"s(\d+)_train.log", p).group(1)): seed_row(p)
          for p in sorted(glob.glob(os.path.join(folder, "s*_train.log")))}
  lines = ["| seed | stopped at step | reason | compile s | process start to policy, s | success (hardest, 100 trials) |",
           "|---:|---:|---|---:|---:|---:|"]
  for seed, r in sorted(rows.items()):
    cell = lambda v, fmt: fmt.format(v) if v is not None else "-"
    lines.append(f"| {seed} | {cell(r['step'], '{:,}')} | {r['reason']} | {cell(r['compile_s'], '{:.0f}')} | "
                 f"{cell(r['process_wall_s'], '{:.0f}')} | {cell(r['hardest_success'], '{:.2f}')} |")
  solved = [r["process_wall_s"] for r in rows.values() if r["hardest_success"] is not None
            and r["hardest_success"] >= EARLY_STOP_SUCCESS and r["process_wall_s"] is not None]
  median = statistics.median(solved) if len(solved) == len(rows) and rows else None
  lines.append(f"| median | | | | {median:.0f} | |" if median is not None else
               f"| median | | | | - ({len(solved)} of {len(rows)} seeds solved) | |")
  head = log_header(folder, "s*_train.log", slice(0, 2))
  write_summary(folder, "time_to_solve", f"Time to solve.\n```\n{head}\n```\nCommands: `bash scripts/gpu_time_to_solve.sh`, "
                f"then `python scripts/summarize_time_to_solve.py {folder}`.\n\n", lines,
                {"seeds": rows, "median_process_wall_s": median})


if __name__ == "__main__":
  main(sys.argv[1])

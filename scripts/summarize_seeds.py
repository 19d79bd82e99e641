"""Table of a multi-seed result folder (written by scripts/gpu_train.sh): per seed, the hardest-
staircase evaluation and the training wall time; prints Markdown and writes DIR/summary.md.

    python scripts/summarize_seeds.py results/asc-inc-cog-seeds
"""

from __future__ import annotations

import argparse
import glob
import json
import os
import re

from results_table import write_summary


def _from_log(log_path: str, pattern: str) -> str:
  text = open(log_path).read() if os.path.exists(log_path) else ""
  m = re.search(pattern, text)
  return m.group(1) if m else "-"


def rows(folder: str) -> list[str]:
  out = []
  for path in sorted(glob.glob(os.path.join(folder, "*_eval_hardest.json"))):
    r = json.load(open(path))
    m = r["metrics"]
    name = os.path.basename(path)[: -len("_eval_hardest.json")]
    seed = json.load(open(os.path.join(folder, f"{name}_run.json")))["seed"]
    f = lambda k, d=3: f"{m[k]['mean']:.{d}f} +- {m[k]['std']:.{d}f}"
    log = os.path.join(folder, f"{name}_train.log")
    device, wall = _from_log(log, r"device: ([^,]+),"), _from_log(log, r"train wall_s (\d+)")
    out.append(f"| {seed} | {r['policy_step']:,} | {wall} | "
               f"{f('progress')} | {m['success']['mean']:.2f} | {f('cog_deviation')} | {f('pitch_rate', 2)} | "
               f"{m['tipped_over']['mean']:.2f} | {device} {r['date'][:10]} |")
  return out


def main(argv=None) -> int:
  p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  p.add_argument("folder")
  args = p.parse_args(argv)
  table = ["| seed | steps asked | train wall s (with compile) | progress | success | COG deviation (m) | pitch rate (rad/s) | tip-overs | device, date |",
           "|---|---|---|---|---|---|---|---|---|", *rows(args.folder)]
  write_summary(args.folder, "summary",
                f"Hardest staircase, 100 trials per seed (`python scripts/summarize_seeds.py {args.folder}`)\n\n",
                table)
  return 0


if __name__ == "__main__":
  raise SystemExit(main())

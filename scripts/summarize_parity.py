"""Parity table from gpu_parity.sh's evaluation files: success on the hardest staircase per seed,
ours (train.run) against Brax's ppo.train / sac.train, with each run's training wall time.

    python scripts/summarize_parity.py results/runtime-parity
"""

from __future__ import annotations

import glob
import json
import os
import re
import sys

from results_table import log_header, write_summary


def main(folder: str) -> None:
  rows = {}
  for path in sorted(glob.glob(os.path.join(folder, "*_eval_hardest.json"))):
    impl, seed = re.match(r"(\w+?)_s(\d+)_eval_hardest.json", os.path.basename(path)).groups()
    r = json.load(open(path))
    log = open(path.replace("_eval_hardest.json", "_train.log")).read()
    wall = re.search(r"train wall_s (\d+)", log)
    rows.setdefault(impl, {})[int(seed)] = {"success": r["metrics"]["success"]["mean"],
                                            "progress": r["metrics"]["progress"]["mean"],
                                            "tipped": r["metrics"]["tipped_over"]["mean"],
                                            "train_wall_s": int(wall.group(1)) if wall else None}
  lines = ["| trainer | seed | success (hardest, 100 trials) | progress | tip-overs | train wall s |",
           "|---|---:|---:|---:|---:|---:|"]
  for impl, seeds in rows.items():
    for seed, r in sorted(seeds.items()):
      lines.append(f"| {impl} | {seed} | {r['success']:.2f} | {r['progress']:.3f} | {r['tipped']:.2f} | "
                   f"{r['train_wall_s']} |")
    mean = sum(r["success"] for r in seeds.values()) / len(seeds)
    lines.append(f"| {impl} | mean of {len(seeds)} | {mean:.2f} | | | |")
  head = log_header(folder, "*_train.log", slice(0, 2))
  command = dict(re.findall(r"--([\w-]+) (\S+)", head))
  write_summary(folder, "parity",
                f"{command.get('algo', 'ppo').upper()} parity, {command['task']}, {command['preset']} preset, "
                f"{int(command['steps']):,} steps.\nFirst run's header:\n```\n{head}\n```\n"
                f"Commands: `ALGO={command.get('algo', 'ppo')} STEPS={command['steps']} bash scripts/gpu_parity.sh`, "
                f"then `python scripts/summarize_parity.py {folder}`.\n\n",
                lines, rows)

if __name__ == "__main__":
  main(sys.argv[1])

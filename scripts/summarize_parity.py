"""Parity table from gpu_parity.sh's evaluation files: success on the hardest staircase per seed,
ours (train.run) against Brax's ppo.train, with each run's training wall time.

    python scripts/summarize_parity.py results/runtime-parity
"""

from __future__ import annotations

import glob
import json
import os
import re
import sys


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
  logs = sorted(glob.glob(os.path.join(folder, "*_train.log")))
  head = "\n".join(open(logs[0]).read().splitlines()[:2]) if logs else ""
  with open(os.path.join(folder, "parity.json"), "w") as f:
    json.dump(rows, f, indent=1)
  with open(os.path.join(folder, "parity.md"), "w") as f:
    f.write(f"PPO parity, asc-inc-cog, gpu preset, 2,000,000 steps.\nFirst run's header:\n```\n{head}\n```\n"
            f"Commands: `bash scripts/gpu_parity.sh`, then `python scripts/summarize_parity.py {folder}`.\n\n")
    f.write("\n".join(lines) + "\n")
  print("\n".join(lines))


if __name__ == "__main__":
  main(sys.argv[1])

"""Speed-up table of gpu_env_speedup.sh: control steps/s of the base and head trees per round, and
the ratio of their medians.

    python scripts/summarize_env_speedup.py results/env-speedup
"""

from __future__ import annotations

import glob
import json
import os
import statistics
import sys

from results_table import write_summary


def rates(folder: str, tree: str) -> list[dict]:
  return [json.load(open(p)) for p in sorted(glob.glob(os.path.join(folder, f"{tree}_r*.json")))]


def main(folder: str) -> None:
  runs = {tree: rates(folder, tree) for tree in ("base", "head")}
  lines = ["| round | base: control steps/s | head: control steps/s | head / base |", "|---:|---:|---:|---:|"]
  for i, (b, h) in enumerate(zip(runs["base"], runs["head"]), 1):
    rb, rh = b["rows"][0]["env_control_steps_per_s"], h["rows"][0]["env_control_steps_per_s"]
    lines.append(f"| {i} | {rb:,} | {rh:,} | {rh / rb:.2f}x |")
  med = {t: statistics.median(r["rows"][0]["env_control_steps_per_s"] for r in rs) for t, rs in runs.items()}
  ratio = med["head"] / med["base"]
  lines.append(f"| median | {med['base']:,.0f} | {med['head']:,.0f} | {ratio:.2f}x |")
  first = runs["head"][0]
  head = f"device: {first['device_kind']}, date: {first['date']}, robots: {first['rows'][0]['envs']:,}"
  write_summary(folder, "env_speedup", f"Environment throughput, head vs base.\n```\n{head}\n```\nCommands: "
                f"`bash scripts/gpu_env_speedup.sh`, then `python scripts/summarize_env_speedup.py {folder}`.\n\n",
                lines, {"median_control_steps_per_s": med, "speedup": round(ratio, 3)})


if __name__ == "__main__":
  main(sys.argv[1])

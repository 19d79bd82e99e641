"""Training throughput per GPU count from gpu_scaling.sh's run databases: the median of the
loop's steps/s over the reports after the first (compilation, evaluations and checkpoints excluded).

    python scripts/summarize_scaling.py results/runtime-scaling
"""

from __future__ import annotations

import glob
import os
import sqlite3
import sys

from results_table import log_header, write_summary


def throughput(db_path: str) -> dict:
  """Median training steps/s of a run's reports after its first (the loop's figure: evaluation
  and checkpoint time excluded)."""
  with sqlite3.connect(db_path) as c:
    rows = c.execute("SELECT step, steps_per_s FROM stats WHERE steps_per_s IS NOT NULL ORDER BY step").fetchall()
  if len(rows) < 2:
    raise SystemExit(f"{db_path}: fewer than 2 training reports")
  rates = sorted(r[1] for r in rows[1:])
  return {"steps_per_s": rates[len(rates) // 2], "from_step": rows[0][0], "to_step": rows[-1][0],
          "reports": len(rates)}


def main(folder: str) -> None:
  out = {}
  for path in sorted(glob.glob(os.path.join(folder, "*.sqlite"))):
    out[os.path.basename(path)[:-7]] = throughput(path)
  base = out.get("g1", {}).get("steps_per_s")
  lines = ["| run | steps/s | speed-up vs 1 GPU | steps measured |", "|---|---:|---:|---:|"]
  for name, r in out.items():
    r["speedup"] = r["steps_per_s"] / base if base else None
    sp = f"{r['speedup']:.2f}x" if base else "-"
    lines.append(f"| {name} | {r['steps_per_s']:,.0f} | {sp} | {r['from_step']:,} -> {r['to_step']:,} |")
  header = log_header(folder, "g*.log", slice(1, 2))
  write_summary(folder, "scaling",
                f"Training throughput (weak scaling, 4,096 robots per GPU). {header}\n"
                f"Command: `bash scripts/gpu_scaling.sh`, then `python scripts/summarize_scaling.py {folder}`.\n\n",
                lines, {"runs": out, "device": header})

if __name__ == "__main__":
  main(sys.argv[1])

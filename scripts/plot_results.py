"""Plot training curves (return, progress, eps, COG deviation vs wall time) of result folders.

python scripts/plot_results.py results/asc-inc-cog results/asc-uni-cog ... --out results/training_curves.png
Each folder holds curve.csv (python -m train.db export RUN --csv) and eval_hardest.json.
Needs the notebooks extra (matplotlib).
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import sys


def read_curve(folder: str) -> dict[str, list[float]]:
  with open(os.path.join(folder, "curve.csv")) as f:
    rows = list(csv.DictReader(f))
  cols = {k: [float(r[k]) if r[k] not in ("", None) else float("nan") for r in rows] for k in rows[0]}
  return cols


def main(argv=None) -> int:
  p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  p.add_argument("folders", nargs="+")
  p.add_argument("--out", required=True)
  args = p.parse_args(argv)
  import matplotlib  # noqa: PLC0415
  matplotlib.use("Agg")
  import matplotlib.pyplot as plt  # noqa: PLC0415
  panels = [("return_mean", "mean episode return"), ("progress_mean", "mean episode progress"),
            ("eps", "curriculum eps"), ("cog_deviation_mean", "COG deviation on stairs (m)")]
  fig, axes = plt.subplots(1, 4, figsize=(16, 3.6))
  for folder in args.folders:
    c = read_curve(folder)
    with open(os.path.join(folder, "eval_hardest.json")) as f:
      ev = json.load(f)["metrics"]
    label = f"{os.path.basename(folder.rstrip('/'))} (hardest: progress {ev['progress']['mean']:.2f})"
    for ax, (key, title) in zip(axes, panels):
      ax.plot(c["wall_s"], c[key], marker=".", label=label)
      ax.set_title(title)
      ax.set_xlabel("wall time (s, incl. compilation)")
  axes[0].legend(fontsize=7, loc="lower right")
  fig.tight_layout()
  fig.savefig(args.out, dpi=110)
  print(f"wrote {args.out}")
  return 0


if __name__ == "__main__":
  sys.exit(main())

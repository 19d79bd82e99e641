"""Success and progress of replicated runs (scripts/gpu_replicate_runs.sh) on each scene: IQM over
seeds of each run's mean over its trials [95 % stratified bootstrap CI], as the study report
computes them. Prints a Markdown table and writes it to FOLDER/summary.md.

cd scripts && python summarize_replicas.py ../results/terrain/mixed-replicas
"""

from __future__ import annotations

import argparse
import glob
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from train.study.report import ci_text  # noqa: E402
from train.study.statistics import LEVEL, iqm_intervals  # noqa: E402


def per_scene(folder: str) -> dict[str, dict[str, list[float]]]:
  """{scene: {metric: one mean per run}} from every run folder's eval-*.json."""
  out: dict[str, dict[str, list[float]]] = {}
  for path in sorted(glob.glob(os.path.join(folder, "*", "eval-*.json"))):
    r = json.load(open(path))
    for m in ("success", "progress"):
      out.setdefault(r["scene"], {}).setdefault(m, []).append(r["metrics"][m]["mean"])
  return out


def table(folder: str) -> list[str]:
  lines = [f"| scene | runs | success IQM [{LEVEL:.0%} CI] | progress IQM |", "|---|---|---|---|"]
  for scene, figs in sorted(per_scene(folder).items(), key=lambda kv: (kv[0] != "hardest", kv[0])):
    est = iqm_intervals(figs)
    lines.append(f"| {scene} | {len(figs['success'])} | {ci_text(est['success'])} | {ci_text(est['progress'])} |")
  return lines


def main(argv: list[str] | None = None) -> int:
  p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  p.add_argument("folder")
  args = p.parse_args(argv)
  lines = table(args.folder)
  if len(lines) == 2:
    print(f"error: no eval-*.json under {args.folder}/*/", file=sys.stderr)
    return 2
  text = "\n".join([f"Written by `cd scripts && python summarize_replicas.py {args.folder}`.", "", *lines]) + "\n"
  open(os.path.join(args.folder, "summary.md"), "w").write(text)
  print(text)
  return 0


if __name__ == "__main__":
  sys.exit(main())

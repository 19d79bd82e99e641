"""`python -m train.study STUDY --plan [--set KEY=VALUE]`: validate a study (a YAML path, or the
NAME of one in configs/studies/) and list its runs, one `train.run` command each. Running studies
(on a Dask cluster) is not built yet."""

from __future__ import annotations

import argparse
import os
import shlex
import sys

from mjx_tracks.envs.config import ConfigError
from train.study.spec import cells, load_study


def parser() -> argparse.ArgumentParser:
  p = argparse.ArgumentParser(prog="python -m train.study", description=__doc__.splitlines()[0])
  p.add_argument("study", help="the study's YAML file, e.g. configs/studies/paper.yaml")
  p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                 help="top-level override, e.g. --set seeds=[0,1] or --set retries=2")
  p.add_argument("--plan", action="store_true", help="list the runs and stop")
  p.add_argument("--root", default="studies", help="where study folders go (default ./studies)")
  return p


def main(argv=None) -> int:
  args = parser().parse_args(argv)
  try:
    spec = load_study(args.study, tuple(args.set))
  except ConfigError as e:
    print(f"error: {e}", file=sys.stderr)
    return 2
  if not args.plan:
    print("error: running a study is not built yet; --plan lists its runs", file=sys.stderr)
    return 2
  folder = os.path.join(args.root, spec.name)
  runs = cells(spec)
  budgets = ", ".join(f"{g.name} {len(g.steps)}" for g in spec.groups)
  print(f"study {spec.name}: {len(runs)} runs = {len(spec.tasks)} tasks x {len(spec.seeds)} seeds x budgets "
        f"per group ({budgets}); retries per run: {spec.retries} -> {folder}")
  for c in runs:
    args_ = c.run_args(os.path.join(folder, "runs", c.id.replace("/", "_")), os.path.join(folder, "study.sqlite"))
    print(f"{c.id}: python -m train.run {shlex.join(args_)}")
  return 0


if __name__ == "__main__":
  sys.exit(main())

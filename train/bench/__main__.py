"""`python -m train.bench NAME [options] [--out FILE]`: run one benchmark (NAME: env, physics,
scaling, ablate, time-to-solve, baselines, speeds, gate (exits 1 if a physics oracle fails),
contacts (exits 1 if a scene kind touches more contacts than the slots keep), gym, group; `python -m
train.bench NAME --help` for its options) and write its rows, with device, command and date, to FILE
(default results/bench/NAME-<device kind>.json)."""

from __future__ import annotations

import argparse
import sys

from train.bench import ablate, baselines, contacts, env, gate, group, gym, physics, scaling, speeds, time_to_solve
from train.bench.result import BenchInputError, default_path, write_result

BENCHES = {"env": env, "physics": physics, "scaling": scaling, "ablate": ablate, "time-to-solve": time_to_solve,
           "baselines": baselines, "speeds": speeds, "gate": gate, "contacts": contacts, "gym": gym, "group": group}


def parser() -> argparse.ArgumentParser:
  p = argparse.ArgumentParser(prog="python -m train.bench", description=__doc__,
                              formatter_class=argparse.RawDescriptionHelpFormatter)
  sub = p.add_subparsers(dest="bench", required=True, metavar="NAME")
  for name, module in BENCHES.items():
    summary = " ".join(module.__doc__.split("\n\n")[0].split()).partition(": ")[2]
    q = sub.add_parser(name, help=summary.split(". ")[0], description=module.__doc__,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    module.add_args(q)
    q.add_argument("--out", help="result file (default results/bench/NAME-<device kind>.json)")
  return p


def main(argv: list[str] | None = None) -> int:
  args = parser().parse_args(argv)
  from mjx_tracks import compile_cache  # noqa: PLC0415
  compile_cache.enable()
  try:
    rows, fields = BENCHES[args.bench].run(args)
  except BenchInputError as e:
    print(f"error: {e}", file=sys.stderr)
    return 2
  out = args.out or default_path(args.bench)
  write_result(out, rows, bench=args.bench, **fields)
  print(f"wrote {out}", file=sys.stderr)
  return 1 if fields.get("pass") is False else 0  # a failed gate


if __name__ == "__main__":
  sys.exit(main())

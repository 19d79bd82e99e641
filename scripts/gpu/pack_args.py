"""`python scripts/gpu/pack_args.py ALGO [STUDY]`: the `train.run` arguments of STUDY's (default
paper-packed, its baselines left out) first pack of ALGO's runs, shell-quoted on one line, as the
study would run that program (train.study.spec.pack_train_args): what the GPU drivers
(sac_evals.sh, solver_loop.sh, mps_pair.sh) run as the study's program. Exit 2, with one line on
stderr, where the study has no such pack."""

import shlex
import sys

from train.study.spec import cells, load_study, pack_train_args, packs_of


def study_pack(algo: str, study: str = "paper-packed"):
  """(the study's spec, its first pack of ALGO's runs, or None)."""
  spec = load_study(study, ("baselines=[]",))
  return spec, next((p for p in packs_of([c for c in cells(spec) if not c.is_baseline]) if p[0].algo == algo), None)


def pack_args(algo: str, study: str = "paper-packed") -> list[str] | None:
  pack = study_pack(algo, study)[1]
  return None if pack is None else pack_train_args(pack)


def main(argv: list[str]) -> int:
  if not 1 <= len(argv) <= 2:
    print("usage: python scripts/gpu/pack_args.py ALGO [STUDY]", file=sys.stderr)
    return 2
  args = pack_args(*argv)
  if args is None:
    study = argv[1] if len(argv) > 1 else "paper-packed"
    print(f"error: study {study} has no pack of {argv[0]} runs", file=sys.stderr)
    return 2
  print(shlex.join(args))
  return 0


if __name__ == "__main__":
  sys.exit(main(sys.argv[1:]))

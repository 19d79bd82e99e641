"""Whether a program of several runs fits a device before a GPU is spent on it: the memory XLA
plans for the vmapped training step of `train.run --seeds ... [--tasks ...]` (its donated states,
its temporaries), compiled here for this machine's backend (XLA:CPU's plan is an estimate of
XLA:GPU's). Nothing is trained or written.

    python scripts/analysis/group_memory.py --tasks asc-inc-cog,des-inc-ang --seeds 0,1,2 --preset gpu
    (any train.run arguments of a program; --out is not needed)
"""

from __future__ import annotations

import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
from mjx_tracks.envs.config import ConfigError  # noqa: E402
from train.core.group import build_group, group_tasks, lower_group, state_bytes  # noqa: E402
from train.core.plan import RunError  # noqa: E402
from train.run import group_plans, parser  # noqa: E402


def main(argv: list[str] | None = None) -> int:
  args = parser().parse_args(argv)
  if args.seeds is None:
    print("error: give the program's --seeds (and --tasks or --task)", file=sys.stderr)
    return 2
  try:
    plans = group_plans(args)
    t = build_group(plans)
  except (RunError, ConfigError) as e:
    print(f"error: {e}", file=sys.stderr)
    return 2
  t0 = time.time()
  memory = lower_group(t, len(plans), group_tasks(t, plans)).compile().memory_analysis()
  size = {k: getattr(memory, f"{k}_size_in_bytes") for k in ("argument", "temp", "output")}
  print(f"{len(plans)} runs of {plans[0].num_envs:,} envs ({plans[0].algo}, {plans[0].preset_name} preset), compiled "
        f"in {time.time() - t0:.0f} s: states {shown(state_bytes(t) * len(plans))} (donated); the update plans "
        f"arguments {shown(size['argument'])}, temporaries {shown(size['temp'])}, outputs {shown(size['output'])} "
        f"(aliased to the arguments); {shown(size['argument'] + size['temp'])} in all")
  return 0


def shown(n: int) -> str:
  """Bytes as GB (two decimals), or MB below 0.1 GB."""
  return f"{n / 1e9:.2f} GB" if n >= 1e8 else f"{n / 1e6:.2f} MB"


if __name__ == "__main__":
  sys.exit(main())

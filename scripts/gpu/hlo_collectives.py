"""Counts the cross-device collectives in a run's compiled training step by how many loops deep they
sit: one inside the env step's own loops (MJX's solver) makes every iteration wait for all devices.

  PYTHONPATH=. XLA_FLAGS=--xla_force_host_platform_device_count=2 JAX_PLATFORMS=cpu \
    python scripts/gpu/hlo_collectives.py --task asc-inc-cog --preset cpu --num-envs 8
"""

from __future__ import annotations

import collections
import re
import sys

from train.core.build import build
from train.core.plan import plan_run
from train.run import parser

COLLECTIVES = ("all-reduce", "all-gather", "all-to-all", "collective-permute", "reduce-scatter")


def computations(hlo: str) -> dict[str, str]:
  """HLO computation name -> its text."""
  parts = re.split(r"\n(?=(?:ENTRY )?%?[\w.\-]+ [^\n]*\{\n)", hlo)
  out = {}
  for part in parts:
    m = re.match(r"(?:ENTRY )?%?([\w.\-]+) ", part)
    if m:
      out[m.group(1)] = part
  return out


def loop_depths(comps: dict[str, str]) -> dict[str, int]:
  """Computation name -> how many while loops it is nested in (its deepest call path)."""
  edges = {n: [(m, 1) for m in re.findall(r"(?:body|condition)=%?([\w.\-]+)", t)]
           + [(m, 0) for m in re.findall(r"(?:to_apply|calls)=%?([\w.\-]+)", t)]
           + [(m.strip().lstrip("%"), 0) for b in re.findall(r"branch_computations=\{([^}]*)\}", t)
              for m in b.split(",")] for n, t in comps.items()}
  depth = {n: 0 for n in comps}
  for _ in range(len(comps)):  # longest paths in a call DAG: relax until nothing changes
    changed = False
    for n, out in edges.items():
      for m, d in out:
        if m in depth and depth[n] + d > depth[m]:
          depth[m], changed = depth[n] + d, True
    if not changed:
      break
  return depth


def count(hlo: str) -> dict[int, collections.Counter]:
  """Loop depth -> counts of each collective op at that depth."""
  comps = computations(hlo)
  depth = loop_depths(comps)
  out = collections.defaultdict(collections.Counter)
  for name, text in comps.items():
    for op in COLLECTIVES:
      out[depth[name]][op] += len(re.findall(rf" {op}(?:-start)?\(", text))
  return dict(sorted(out.items()))


def main(argv: list[str]) -> None:
  plan = plan_run(parser().parse_args(argv))
  t = build(plan)
  import jax  # noqa: PLC0415
  from train.core.build import shaped_state  # noqa: PLC0415
  jitted = jax.jit(t.learner.update, in_shardings=(t.shardings,), donate_argnums=0)
  hlo = jitted.lower(shaped_state(t)).compile().as_text()
  print(f"{t.mesh.devices.size} x {jax.default_backend()}, {plan.task}, {plan.algo}, {plan.num_envs} envs")
  print("  loops deep: " + ", ".join(COLLECTIVES))
  for depth, c in count(hlo).items():
    print(f"  {depth:10d}: " + ", ".join(str(c[op]) for op in COLLECTIVES))


if __name__ == "__main__":
  main(sys.argv[1:])

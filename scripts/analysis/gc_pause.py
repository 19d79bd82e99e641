"""How long Python's collector pauses a split PPO update's host loop (train.core.algos.ppo_split):
builds the `cpu` preset's tiny run (tests/helpers.py TINY settings), compiles its split update
(which calls gc.freeze() once compiled), then prints the objects the collector tracks and the
seconds of one full collection (gc.collect()), before and after undoing the freeze (gc.unfreeze()).
Usage: JAX_PLATFORMS=cpu python scripts/analysis/gc_pause.py"""

from __future__ import annotations

import gc
import os
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path[:0] = [ROOT, os.path.join(ROOT, "tests")]


def _full_pass() -> float:
  t0 = time.perf_counter()
  gc.collect()
  return time.perf_counter() - t0


def main() -> None:
  import tempfile  # noqa: PLC0415
  from helpers import TINY  # noqa: PLC0415
  from train.core.algos.ppo_split import SplitUpdate  # noqa: PLC0415
  from train.core.build import build, shaped_state  # noqa: PLC0415
  from train.core.plan import plan_run  # noqa: PLC0415
  from train.run import parser  # noqa: PLC0415
  with tempfile.TemporaryDirectory() as out:
    t = build(plan_run(parser().parse_args(["--task", "asc-inc-cog", "--preset", "cpu", *TINY, "--out", out])))
    SplitUpdate(t.learner, t.core, t.mesh, t.shardings).compile(shaped_state(t))
    print(f"frozen: {gc.get_freeze_count():,} objects; a full collection {_full_pass():.3f} s")
    gc.unfreeze()
    print(f"unfrozen: {len(gc.get_objects()):,} objects tracked; a full collection {_full_pass():.3f} s")


if __name__ == "__main__":
  main()

"""Issue 30, compilation: how fast PPO's update trains fused (one program, train.core.algos.ppo) and
split (train.core.algos.ppo_split: 5 programs, or 4 with the auto-reset inside the env step's),
in one process, alternated (fused, split-5, split-4, twice). Per variant: the update's seconds and
steps/s over UPDATES updates after 2 warm-up updates; the median seconds its call took to return
(a host loop that waits for the device returns as late as the update ends: its dispatches then add
to the update's time); the compile seconds in this process (not from an empty cache: JAX and XLA
keep what earlier variants compiled; scripts/gpu/compile_flags.py times that).
Usage (GPU host): python scripts/gpu/split_update_speed.py OUT [--updates 4] [--order V,...] [train.run arguments ...]
(default: --task asc-inc-cog --preset gpu). Writes OUT/split-update-speed.json with device, command, date."""

from __future__ import annotations

import datetime
import json
import os
import shlex
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))

VARIANTS = ("fused", "split-5", "split-4")  # the default order, twice; --order NAME,... (also split-5-serial:
#                                               its programs compiled one at a time) runs those once each


def _compile(t, name: str):
  import jax  # noqa: PLC0415
  from train.core.algos.ppo_split import SplitUpdate  # noqa: PLC0415
  from train.core.build import shaped_state  # noqa: PLC0415
  if name == "fused":
    return jax.jit(t.learner.update, donate_argnums=0).lower(shaped_state(t)).compile()
  split = SplitUpdate(t.learner, t.core, t.mesh, t.shardings, reset_apart=name.startswith("split-5"))
  return split.compile(shaped_state(t), threads=1 if name.endswith("serial") else None)


def _measure(t, name: str, updates: int) -> dict:
  import jax  # noqa: PLC0415
  import numpy as np  # noqa: PLC0415
  from train.core.build import init_state  # noqa: PLC0415
  t0 = time.time()
  update = _compile(t, name)
  compile_s = time.time() - t0
  state = init_state(t, 0)
  for _ in range(2):
    state, _ = update(state)
  jax.block_until_ready(state)
  returned, t0 = [], time.time()
  for _ in range(updates):
    t1 = time.time()
    state, _ = update(state)
    returned.append(time.time() - t1)
  jax.block_until_ready(state)
  seconds = (time.time() - t0) / updates
  return {"update_s": round(seconds, 4), "steps_per_s": round(t.learner.steps_per_update / seconds),
          "call_returned_s": round(float(np.median(returned)), 4), "compile_s_in_process": round(compile_s, 1)}


def main() -> None:
  if len(sys.argv) < 2 or sys.argv[1].startswith("-"):
    sys.exit(__doc__)
  out, rest = sys.argv[1], sys.argv[2:]
  updates, order = 4, VARIANTS * 2
  while rest[:1] in (["--updates"], ["--order"]):
    if rest[0] == "--updates":
      updates = int(rest[1])
    else:
      order = tuple(rest[1].split(","))
    rest = rest[2:]
  import jax  # noqa: PLC0415
  from train.core.build import build  # noqa: PLC0415
  from train.core.plan import plan_run  # noqa: PLC0415
  from train.run import parser  # noqa: PLC0415
  args = rest or ["--task", "asc-inc-cog", "--preset", "gpu"]
  t = build(plan_run(parser().parse_args([*args, "--out", os.path.join(out, "run")])))
  results: dict[str, list] = {name: [] for name in order}
  for name in order:
    results[name].append(_measure(t, name, updates))
    print(name, results[name][-1], flush=True)
  os.makedirs(out, exist_ok=True)
  json.dump({"device": f"{jax.devices()[0].device_kind} x {jax.device_count()}, JAX {jax.__version__}",
             "command": "python scripts/gpu/split_update_speed.py " + shlex.join(sys.argv[1:]),
             "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
             "steps_per_update": t.learner.steps_per_update, "updates_timed": updates, "variants": results},
            open(os.path.join(out, "split-update-speed.json"), "w"), indent=1)


if __name__ == "__main__":
  main()

"""Issue 30, what a timed checkpoint round of a program of many runs costs: every run's whole-state
checkpoint (train.core.checkpoints.RunCheckpoints, replay buffer included) after one update, taken
as the program's loop took it before 2026-11-28 (each run's state sliced leaf by leaf on the device,
then fetched) and as it takes it since (one transfer of the program's states, then each run's host
slice: train.core.group_loop.GroupLoop._checkpoint_round), in one process, one after the other,
twice each (alternating, after a warm-up round). Writes OUT/checkpoint-round.json with the device, command and date.

Usage (GPU host): python scripts/gpu/checkpoint_round.py OUT -- TRAIN.RUN ARGS (with --seeds)
E.g. the paper study's SAC program: -- --tasks asc-inc-cog,asc-uni-cog,des-inc-ang,des-uni-ang --algo sac
--preset paper --seeds 0,1,2,3,4 --hp max_replay_size=20000 --out /tmp/cr"""

from __future__ import annotations

import datetime
import json
import os
import pathlib
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
import jax  # noqa: E402

from train.core.checkpoints import RunCheckpoints  # noqa: E402
from train.core.group import build_group, compile_group, group_tasks, init_group  # noqa: E402
from train.core.group_loop import run_slice  # noqa: E402
from train.core.mesh import to_host  # noqa: E402
from train.run import group_plans, parser  # noqa: E402


def leafwise(states, i: int):
  """Run i's state sliced leaf by leaf on the device (the loop's way before 2026-11-28)."""
  return jax.tree_util.tree_map(lambda x: x[i], states)


def round_seconds(t, states, folder: pathlib.Path, step: int, way: str) -> float:
  """Seconds to checkpoint every run of the program at `step`, the old way or the new."""
  t0 = time.perf_counter()
  host = to_host(states) if way == "new" else None
  for i in range(jax.tree_util.tree_leaves(states)[0].shape[0]):
    state = run_slice(host, i) if way == "new" else to_host(leafwise(states, i))
    RunCheckpoints(str(folder / f"run{i}")).save(step, state, t.learner.policy_params(state), {"way": way})
  return time.perf_counter() - t0


def main() -> int:
  argv = sys.argv[1:]
  if "--" not in argv or len(argv[:argv.index("--")]) != 1:
    print(__doc__.split("\n\n")[1], file=sys.stderr)
    return 2
  out, train_argv = pathlib.Path(argv[0]), argv[argv.index("--") + 1:]
  plans = group_plans(parser().parse_args(train_argv))
  t = build_group(plans)
  tasks = group_tasks(t, plans)
  update, _ = compile_group(t, len(plans), tasks=tasks)
  states = jax.block_until_ready(update(init_group(t, plans, tasks))[0])
  round_seconds(t, states, out / "ckpt" / "warm-up", 0, "new")  # orbax's first save sets itself up
  result = {"device": str(jax.devices()[0].device_kind), "jax": jax.__version__, "runs": len(plans),
            "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "command": "python scripts/gpu/checkpoint_round.py " + " ".join(argv), "rounds": []}
  for step, way in enumerate(("old", "new", "old", "new"), start=1):
    result["rounds"].append({"way": way, "seconds": round(round_seconds(t, states, out / "ckpt" / way, step, way), 2)})
    print(result["rounds"][-1], flush=True)
    (out / "checkpoint-round.json").write_text(json.dumps(result, indent=1) + "\n")
  return 0


if __name__ == "__main__":
  sys.exit(main())

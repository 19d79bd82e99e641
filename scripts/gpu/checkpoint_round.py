"""Issue 30, what a timed checkpoint round of a program of many runs costs the training: every run's
whole-state checkpoint (replay buffer included) from one transfer of the program's states, written
the way the loop wrote it before 2026-11-29 (each run's slice of the host states taken on the device
whole, as run_slice did while Brax's UInt64 count kept two leaves there; one orbax array per leaf of
the state; the curriculum's figures through jax.numpy; each save waited for) and the way it writes
it since (train.core.group_loop.run_slice: numpy views; train.core.loop.Checkpointer.save(...,
wait=False): the leaves' bytes as one array, written in the background). For each round: the seconds the training loop is held ("blocking") and the seconds
until every run's checkpoint is on disk ("on_disk"). In one process, alternating, twice each, after
a warm-up round of each way; the runs' fresh states (train.core.group.init_group: the shapes the
program checkpoints). Writes OUT/checkpoint-round.json with the device, command and date.

Usage (GPU host): python scripts/gpu/checkpoint_round.py OUT -- TRAIN.RUN ARGS (with --seeds)
E.g. the paper study's SAC program: -- --tasks asc-inc-cog,asc-uni-cog,des-inc-ang,des-uni-ang --algo sac
--preset paper --seeds 0,1,2,3,4,5,6,7,8,9 --hp max_replay_size=20000 --out /tmp/cr"""

from __future__ import annotations

import dataclasses
import datetime
import json
import os
import pathlib
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
import orbax.checkpoint as ocp  # noqa: E402

from train.core.checkpoints import RunCheckpoints, _plain  # noqa: E402
from train.core.group import build_group, group_tasks, init_group  # noqa: E402
from train.core.group_loop import _device_slice, run_slice  # noqa: E402
from train.core.loop import Checkpointer  # noqa: E402
from train.core.mesh import to_host  # noqa: E402
from train.run import group_plans, parser  # noqa: E402


def old_save(ckpts: RunCheckpoints, t, host, step: int) -> None:
  """One run's checkpoint as Checkpointer.save wrote it before 2026-11-29."""
  glob = jax.tree_util.tree_map(lambda x: x[0], host.env_state.info["global"])
  figures = {part: {f.name: jnp.asarray(getattr(getattr(glob, part), f.name)).tolist()
                    for f in dataclasses.fields(getattr(glob, part))} for part in ("curriculum", "normalizer")}
  leaves = jax.tree_util.tree_flatten_with_path(host)[0]
  arrays = {f"leaf_{i:05d}": np.asarray(x) for i, (_, x) in enumerate(leaves) if np.size(x)}
  layout = [{"path": jax.tree_util.keystr(p), "shape": list(np.shape(x)), "dtype": str(np.asarray(x).dtype)}
            for p, x in leaves]
  ckpts.mgr.save(step, args=ocp.args.Composite(
      state=ocp.args.StandardSave(arrays), params=ocp.args.StandardSave(_plain(t.learner.policy_params(host))),
      meta=ocp.args.JsonSave({"step": step, "layout": layout, "global": figures})), force=True)
  ckpts.mgr.wait_until_finished()


def round_seconds(t, states, folder: pathlib.Path, step: int, way: str, n: int) -> dict:
  """{"blocking", "on_disk"}: seconds of one round of n runs' checkpoints, the old way or the new."""
  t0 = time.perf_counter()
  host = to_host(states)
  if way == "old":
    for i in range(n):
      old_save(RunCheckpoints(str(folder / f"run{i}")), t, to_host(_device_slice(host, i)), step)
    blocking = time.perf_counter() - t0
    return {"blocking": round(blocking, 2), "on_disk": round(blocking, 2)}
  savers = [Checkpointer(RunCheckpoints(str(folder / f"run{i}")), {"way": way}, t.learner, lambda s: None, 60.0)
            for i in range(n)]
  for i, c in enumerate(savers):
    c.save(run_slice(host, i), step, wait=False)
  blocking = time.perf_counter() - t0
  for c in savers:
    c.settle()
  return {"blocking": round(blocking, 2), "on_disk": round(time.perf_counter() - t0, 2)}


def main() -> int:
  argv = sys.argv[1:]
  if "--" not in argv or len(argv[:argv.index("--")]) != 1:
    print(__doc__.split("\n\n")[1], file=sys.stderr)
    return 2
  out, train_argv = pathlib.Path(argv[0]), argv[argv.index("--") + 1:]
  plans = group_plans(parser().parse_args(train_argv))
  t = build_group(plans)
  states = jax.block_until_ready(init_group(t, plans, group_tasks(t, plans)))
  n = len(plans)
  for way in ("old", "new"):  # orbax's first save sets itself up
    round_seconds(t, states, out / "ckpt" / f"warm-up-{way}", 0, way, n)
  result = {"device": str(jax.devices()[0].device_kind), "jax": jax.__version__, "runs": n,
            "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "command": "python scripts/gpu/checkpoint_round.py " + " ".join(argv), "rounds": []}
  for step, way in enumerate(("old", "new", "old", "new"), start=1):
    result["rounds"].append({"way": way, **round_seconds(t, states, out / "ckpt" / way, step, way, n)})
    print(result["rounds"][-1], flush=True)
    (out / "checkpoint-round.json").write_text(json.dumps(result, indent=1) + "\n")
  return 0


if __name__ == "__main__":
  sys.exit(main())

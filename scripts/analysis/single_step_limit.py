"""How high a single step each robot can climb up and drive down: the scripted stair controller and
full belt speed with the joints held, on one step (a 1-step staircase: riser h, then a 3 m landing)
of each riser h in a grid, from the tasks' spawn. Prints a table and writes JSON with the device,
command and date.

Usage (CPU is fine): python scripts/analysis/single_step_limit.py --out results/terrain/single-step-limit.json
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import json
import os
import platform
import sys
import time

import jax
import jax.numpy as jnp
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
from mjx_tracks import compile_cache  # noqa: E402
from mjx_tracks.envs.config import default_config  # noqa: E402
from mjx_tracks.robots import get_robot  # noqa: E402
from mjx_tracks.sim.simulator import staircase_simulator  # noqa: E402
from mjx_tracks.tools.drive import CONTROLLERS, DriveSetup, scripted_rollouts, summarize  # noqa: E402
from scenes import staircase as sc  # noqa: E402

TREAD = 0.30  # m; a 1-step staircase's step is its landing, so the tread plays no part
CONTROL_PERIOD = 0.1  # s, as `python -m mjx_tracks.tools.drive`


def outcomes(robot_name: str, direction: str, risers: np.ndarray, seconds: float) -> dict[str, list[dict]]:
  """{controller: [summary per riser]} of one robot and direction."""
  defaults = default_config()
  sim = staircase_simulator(get_robot(robot_name), defaults.physics)
  n = len(risers)
  stairs = sc.Staircase(jnp.full(n, TREAD, jnp.float32), jnp.asarray(risers, jnp.float32), jnp.ones(n, jnp.int32))
  setup = DriveSetup(sim, stairs, direction, CONTROL_PERIOD, defaults.episode.goal_tolerance)
  out = {}
  for controller in CONTROLLERS:
    qpos = scripted_rollouts(setup, round(seconds / CONTROL_PERIOD), controller)
    out[controller] = [
        {"riser_m": round(float(h), 3),
         **summarize(dataclasses.replace(setup, stairs=sc.Staircase(TREAD, float(h), 1)), q)}
        for h, q in zip(risers, qpos)]
  return out


def highest(rows: list[dict]) -> float | None:
  """The highest riser below which every riser was passed (m), or None if the lowest failed."""
  best = None
  for r in rows:
    if not r["goal_reached"]:
      break
    best = r["riser_m"]
  return best


def main() -> int:
  p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  p.add_argument("--robots", default="1,2")
  p.add_argument("--risers", default="0.10,0.40,0.025", help="lowest, highest, step (m)")
  p.add_argument("--seconds", type=float, default=15.0)
  p.add_argument("--out", help="JSON path")
  args = p.parse_args()
  lo, hi, step = (float(x) for x in args.risers.split(","))
  risers = np.round(np.arange(lo, hi + step / 2, step), 3)
  compile_cache.enable()
  t0, results = time.time(), {}
  for robot in args.robots.split(","):
    for direction in ("up", "down"):
      res = outcomes(robot, direction, risers, args.seconds)
      results[f"robot {robot} {direction}"] = {c: {"highest_m": highest(rows), "rows": rows} for c, rows in res.items()}
      print(f"robot {robot} {direction}: " + ", ".join(
          f"{c} passes every riser up to {results[f'robot {robot} {direction}'][c]['highest_m']} m" for c in res),
          flush=True)
  record = {"command": "python " + " ".join(sys.argv), "device": f"{jax.devices()[0].device_kind} "
            f"({platform.processor() or platform.machine()}, {os.cpu_count()} cores)",
            "date": datetime.date.today().isoformat(), "seconds": args.seconds, "tread_m": TREAD,
            "wall_s": round(time.time() - t0, 1), "results": results}
  if args.out:
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    with open(args.out, "w") as f:
      json.dump(record, f, indent=1)
  return 0


if __name__ == "__main__":
  sys.exit(main())

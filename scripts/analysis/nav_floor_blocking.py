"""How often do a navigation task's floor obstacles leave no way round them? For scenes drawn as the
task draws them (uniform, eps = 1), the free-space distance from the spawn to the goal
(scenes.geodesic: the robot as a disc of radius r, not capped by the gap as the task's reward
caps it) around the wall obstacles alone and around the wall and floor obstacles: where the first is finite and the second infinite, the robot can reach
the goal only by driving over a floor obstacle on its belts (a collision if anything else touches
it). Robot 1 is 0.81 m wide (r = 0.41 m: its half-width) and 1.28 m long. With scene.nav_floor_passage
it also gives the share of scenes whose floor obstacles were left out (no layout with a way round
in FLOOR_TRIES draws: parked off the area). Prints a line per r and writes JSON with the device,
command and date.

python scripts/analysis/nav_floor_blocking.py --task nav-obstacles --scenes 4000 --radii 0.41,0.5,0.64 \
    [--set scene.nav_floor_passage=0] --out results/nav/floor-blocking-cpu.json
"""

from __future__ import annotations

import argparse
import datetime
import json
import platform
import sys

import jax
import jax.numpy as jnp
import numpy as np

from mjx_tracks import atomic
from mjx_tracks.envs.config import load_config
from scenes.kinds import scene_kind
from scenes.navigation import WALL_OBSTACLES, path_around
from scenes.world import is_parked


def free_space(states, boxes: int, r: float) -> np.ndarray:
  """Each scene's shortest path (m; inf: none) from its spawn to its goal around its first `boxes`
  boxes, for a disc of radius r (m)."""
  one = lambda s: path_around(s.spawn_pos[:2], s.goal[:2], s.box_pos[:boxes, :2], s.box_size[:boxes, :2], r)  # noqa: E731
  return np.asarray(jax.jit(jax.vmap(one))(states))


def blocked_shares(task: str, scenes: int, radii: list[float], overrides=(), seed: int = 0) -> tuple[list[dict], float]:
  """Per radius: the shares of scenes with no way round the floor obstacles where the wall obstacles
  alone leave one (all areas, hallway, zigzag), and with no way round the wall obstacles alone; and
  the share of scenes whose floor obstacles were left out."""
  cfg = load_config(task, list(overrides))
  scene = scene_kind(cfg.scene.kind).make(cfg.scene)
  if not cfg.scene.nav_floor_obstacles:
    raise SystemExit(f"error: {task} draws no floor obstacles")
  states = jax.jit(jax.vmap(lambda k: scene.sample(k, jnp.float32(1.0))))(jax.random.split(jax.random.PRNGKey(seed), scenes))
  area = np.asarray(states.variant)  # 0 hallway, 1 zigzag
  # with scene.nav_floor_passage, a scene whose FLOOR_TRIES layouts all lacked a way round has its
  # floor obstacles parked off the area
  left_out = np.asarray(is_parked(states.box_pos[:, WALL_OBSTACLES]))
  rows = []
  for r in radii:
    walls = free_space(states, WALL_OBSTACLES, r)
    both = free_space(states, WALL_OBSTACLES + cfg.scene.nav_floor_obstacles, r)
    blocked = np.isfinite(walls) & np.isinf(both)
    rows.append({"radius_m": r, "blocked_by_floor_obstacles": float(blocked.mean()),
                 "hallway": float(blocked[area == 0].mean()), "zigzag": float(blocked[area == 1].mean()),
                 "blocked_by_walls_alone": float(np.isinf(walls).mean())})
  return rows, float(left_out.mean())


def main(argv=None) -> int:
  p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  p.add_argument("--task", default="nav-obstacles")
  p.add_argument("--scenes", type=int, default=4000)
  p.add_argument("--radii", default="0.41,0.5,0.64", help="disc radii (m), comma-separated")
  p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a task config override")
  p.add_argument("--out", help="JSON file to write")
  args = p.parse_args(argv)
  rows, left_out = blocked_shares(args.task, args.scenes, [float(r) for r in args.radii.split(",")], args.set)
  for row in rows:
    print(f"r = {row['radius_m']} m: no way round the floor obstacles in {row['blocked_by_floor_obstacles']:.3f} of "
          f"the scenes (hallway {row['hallway']:.3f}, zigzag {row['zigzag']:.3f}); walls alone "
          f"{row['blocked_by_walls_alone']:.3f}")
  print(f"floor obstacles left out of {left_out:.3f} of the scenes")
  if args.out:
    record = {"task": args.task, "overrides": args.set, "scenes": args.scenes, "rows": rows,
              "floor_obstacles_left_out": left_out, "device": f"{jax.devices()[0]} ({platform.node()})",
              "command": "python " + " ".join(sys.argv), "date": datetime.datetime.now(datetime.timezone.utc).isoformat()}
    atomic.write_json(args.out, record)
  return 0


if __name__ == "__main__":
  raise SystemExit(main())

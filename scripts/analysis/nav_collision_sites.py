"""Where do a navigation policy's collisions happen? For each run folder's evaluation report of a
navigation area (eval-nav-AREA.json: per-trial success, collided and the chassis' final position),
the trials' scenes are drawn again as `train.evaluate` drew them (the run's config, the area's
draw, reset keys split from EVAL_SEED, eps EVAL_EPS) and each collided trial's final chassis
position (where its episode ended: a collision ends it) is set beside the nearest floor obstacle,
wall obstacle and outer wall (2D distance to each footprint, m). A check that the scenes are the
evaluation's: every successful trial must end within `--check-radius` of its scene's goal.
Prints a line per run and area and writes JSON with the device, command and date. CPU, resets only
(no policy is run).

python scripts/analysis/nav_collision_sites.py results/studies/nav/runs/ppo_nav-obstacles_6000000_s* \
    --out results/nav/collision-sites-cpu.json
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import sys

import jax
import numpy as np

from mjx_tracks import atomic
from mjx_tracks.envs.config import from_dict
from mjx_tracks.envs.task_env import TrackedRobotEnv
from scenes.navigation import AREA_HI, AREA_LO, NAV_AREAS, WALL_OBSTACLES
from train.core.run_record import read_run_record
from train.evaluation import EVAL_EPS, EVAL_SEED, scene_programs, trial_keys, trial_starts

KINDS = ("floor obstacle", "wall obstacle", "outer wall")


def footprint_distance(p: np.ndarray, centre: np.ndarray, half: np.ndarray, yaw: np.ndarray) -> np.ndarray:
  """(trials, boxes) 2D distance (m) from points p (trials, 2) to box footprints (trials, boxes)
  given by centre (x, y), half-sizes (x, y) and yaw (rad); 0 inside."""
  d = p[:, None, :] - centre
  c, s = np.cos(yaw), np.sin(yaw)
  local = np.stack([c * d[..., 0] + s * d[..., 1], -s * d[..., 0] + c * d[..., 1]], axis=-1)
  return np.linalg.norm(np.maximum(np.abs(local) - half, 0.0), axis=-1)


def trial_scenes(cfg, area: str, trials: int):
  """The trials' scene states (batched SceneState) of `area` as train.evaluate draws them."""
  (program, draws), = scene_programs(cfg, [area])
  core = TrackedRobotEnv(program)
  starts = jax.jit(lambda keys: trial_starts(core, keys, EVAL_EPS, None, draws[area]))
  return starts(trial_keys(trials, EVAL_SEED)).pipeline_state.scene


def sites(run_dir: str, area: str, check_radius: float) -> dict | None:
  """Collision sites of one run on one area (None where the run has no such report)."""
  path = os.path.join(run_dir, f"eval-{area.replace('/', '-')}.json")
  if not os.path.exists(path):
    return None
  report = json.load(open(path))
  per = {k: np.asarray(v) for k, v in report["per_trial"].items()}
  cfg = from_dict(read_run_record(run_dir)["config"])
  scene = jax.tree_util.tree_map(np.asarray, trial_scenes(cfg, area, len(per["success"])))
  end = np.stack([per["final_x"], per["final_y"]], axis=-1)
  ok = per["success"] > 0
  miss = np.linalg.norm(end[ok] - scene.goal[ok, :2], axis=-1)
  if miss.size and miss.max() > check_radius:
    raise SystemExit(f"error: {run_dir} {area}: a successful trial ends {miss.max():.2f} m from its scene's goal: "
                     "these are not the evaluation's scenes")
  box = footprint_distance(end, scene.box_pos[..., :2], scene.box_size[..., :2], scene.box_yaw)
  outer = np.minimum(end - np.array(AREA_LO), np.array(AREA_HI) - end).min(axis=1)  # to the nearest wall plane
  floor = box[:, WALL_OBSTACLES:].min(axis=1) if box.shape[1] > WALL_OBSTACLES else np.full(len(end), np.inf)
  near = np.stack([floor, box[:, :WALL_OBSTACLES].min(axis=1), outer], axis=-1)  # (trials, 3)
  hit = per["collided"] > 0
  nearest = np.argmin(near[hit], axis=1)
  return {"run": run_dir, "area": area, "trials": int(len(hit)), "success": float(ok.mean()),
          "collided": int(hit.sum()), "success_goal_miss_max_m": float(miss.max()) if miss.size else None,
          "nearest": {k: int((nearest == i).sum()) for i, k in enumerate(KINDS)},
          "collided_distance_m": {k: [round(float(x), 3) for x in near[hit, i]] for i, k in enumerate(KINDS)}}


def main(argv: list[str] | None = None) -> int:
  p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  p.add_argument("runs", nargs="+", help="run folders with eval-nav-AREA.json reports")
  p.add_argument("--check-radius", type=float, default=0.8, help="m: a successful trial ends this near its goal")
  p.add_argument("--out", help="JSON path")
  args = p.parse_args(argv)
  rows = [r for run in args.runs for area in NAV_AREAS if (r := sites(run, f"nav/{area}", args.check_radius))]
  for r in rows:
    print(f"{r['run']} {r['area']}: {r['collided']} of {r['trials']} trials collided; nearest to their end: "
          + ", ".join(f"{k} {n}" for k, n in r["nearest"].items()))
  total = {k: sum(r["nearest"][k] for r in rows) for k in KINDS}
  print(f"all: {sum(r['collided'] for r in rows)} collisions; nearest: {total}")
  if args.out:
    atomic.write_json(args.out, {"device": f"CPU ({platform.processor() or platform.machine()})",
                                 "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
                                 "command": "python " + " ".join(sys.argv), "jax": jax.__version__,
                                 "nearest_all": total, "rows": rows})
  return 0


if __name__ == "__main__":
  raise SystemExit(main())

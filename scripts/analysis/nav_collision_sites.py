"""Where do a navigation policy's collisions happen? For each run folder's evaluation report of a
navigation area (eval-nav-AREA.json: per-trial success, collided and the chassis' final position),
the trials' scenes are drawn again as `train.evaluate` drew them (the run's config, the area's
draw, reset keys split from EVAL_SEED, eps EVAL_EPS) and each collided trial's final chassis
position (where its episode ended: a collision ends it) is set beside the nearest floor obstacle,
wall obstacle and outer wall (2D distance to each footprint, m). A check that the scenes are the
evaluation's: every successful trial must end within `--check-radius` of its scene's goal.
Which obstacle could it have been? Of the robot's colliding geoms only the belts may touch a floor box
(sim/collisions.py), so a floor-box collision needs a non-belt geom (robot 1: the belly) over the
box: `reach` counts each collided trial by which kinds lie within reach of its final chassis
position, a floor box within the non-belt geoms' reach, a wall obstacle or outer wall within any
colliding geom's (each reach: the largest horizontal distance from the chassis origin to a geom's
centre plus its bounding radius, the robot level at rest, plus REACH_SLACK).
How tight is each trial's layout? For each disc radius of `--discs` (m; capped, as the scene caps its
passage, at C / 2 - GAP_MARGIN for the area's gap C), whether a way round the wall and floor obstacles
leads from the spawn to the goal (scenes.navigation: free_space_distance with every box), counted
among the trials that succeeded, collided and timed out (mjx_tracks.metrics.timed_out; a trial that
tipped over is in none).
Prints a line per run and area and writes JSON with the device, command and date. CPU, resets only
(no policy is run).

python scripts/analysis/nav_collision_sites.py results/studies/nav/runs/ppo_nav-obstacles_6000000_s* \
    --out results/nav/collision-sites-cpu.json
(the study's run folders with their reports and policies: `git checkout 236240e --
results/studies/nav/runs`, or the study run again)
"""

from __future__ import annotations

import argparse
import collections
import json
import os

import jax
import jax.numpy as jnp
import numpy as np

from mjx_tracks import atomic
from mjx_tracks.metrics import timed_out
from mjx_tracks.sim.collisions import robot_at_rest
from scenes.navigation import NAV_AREAS, WALL_OBSTACLES, area_corners
from train.core.run_record import run_config
from train.evaluation import EVAL_EPS, EVAL_SEED, report_path, scene_env, trial_keys, trial_starts
from provenance import provenance  # scripts/analysis/provenance.py (this script's folder is on sys.path)

KINDS = ("floor obstacle", "wall obstacle", "outer wall")
REACH_SLACK = 0.05  # m: tilt, and the chassis' travel within the control step that ended the episode


def reaches(core) -> tuple[float, float]:
  """(m, m): how far from the chassis origin the robot's colliding non-belt geoms and all its
  colliding geoms reach, level at rest (module docstring)."""
  m, layout = core.sim.mj_model, core.sim.layout
  data, g = robot_at_rest(m)
  chassis = data.xpos[layout.chassis_body, :2]
  far = np.linalg.norm(data.geom_xpos[g, :2] - chassis, axis=1) + m.geom_rbound[g] + REACH_SLACK
  return float(far[layout.geom_belt[g] < 0].max()), float(far.max())


def footprint_distance(p: np.ndarray, centre: np.ndarray, half: np.ndarray, yaw: np.ndarray) -> np.ndarray:
  """(trials, boxes) 2D distance (m) from points p (trials, 2) to box footprints (trials, boxes)
  given by centre (x, y), half-sizes (x, y) and yaw (rad); 0 inside."""
  d = p[:, None, :] - centre
  c, s = np.cos(yaw), np.sin(yaw)
  local = np.stack([c * d[..., 0] + s * d[..., 1], -s * d[..., 0] + c * d[..., 1]], axis=-1)
  return np.linalg.norm(np.maximum(np.abs(local) - half, 0.0), axis=-1)


def trial_scenes(cfg, area: str, trials: int, discs: tuple[float, ...]):
  """The trials' scene states (batched SceneState) of `area` as train.evaluate draws them, and
  (trials, discs) bool: whether each has a way round every obstacle for a disc of each radius."""
  core, draw = scene_env(cfg, area)
  starts = jax.jit(lambda keys: trial_starts(core, keys, EVAL_EPS, None, draw))
  scene = starts(trial_keys(trials, EVAL_SEED)).pipeline_state.scene
  boxes = scene.box_pos.shape[1]

  def way_round(s):
    return jnp.stack([jnp.isfinite(core.scene.free_space_distance(s, s.spawn_pos, boxes, r)) for r in discs])
  return core, scene, jax.jit(jax.vmap(way_round))(scene)


def sites(run_dir: str, area: str, check_radius: float, discs: tuple[float, ...]) -> dict | None:
  """Collision sites of one run on one area (None where the run has no such report)."""
  path = report_path(run_dir, area, None)
  if not os.path.exists(path):
    return None
  report = json.load(open(path))
  per = {k: np.asarray(v) for k, v in report["per_trial"].items()}
  cfg = run_config(run_dir)
  core, *arrays = trial_scenes(cfg, area, len(per["success"]), discs)
  scene, way = jax.tree_util.tree_map(np.asarray, arrays)
  end = np.stack([per["final_x"], per["final_y"]], axis=-1)
  ok = per["success"] > 0
  miss = np.linalg.norm(end[ok] - scene.goal[ok, :2], axis=-1)
  if miss.size and miss.max() > check_radius:
    raise SystemExit(f"error: {run_dir} {area}: a successful trial ends {miss.max():.2f} m from its scene's goal: "
                     "these are not the evaluation's scenes")
  box = footprint_distance(end, scene.box_pos[..., :2], scene.box_size[..., :2], scene.box_yaw)
  lo, hi = map(np.asarray, area_corners(core.scene.length))  # the area's corners (x, y), m
  outer = np.minimum(end - lo, hi - end).min(axis=1)  # to the nearest wall plane
  floor = box[:, WALL_OBSTACLES:].min(axis=1) if box.shape[1] > WALL_OBSTACLES else np.full(len(end), np.inf)
  near = np.stack([floor, box[:, :WALL_OBSTACLES].min(axis=1), outer], axis=-1)  # (trials, 3)
  hit = per["collided"] > 0
  nearest = np.argmin(near[hit], axis=1)
  body_reach, robot_reach = reaches(core)
  in_reach = near[hit] <= np.array([body_reach, robot_reach, robot_reach])  # (collided, 3)
  reach = collections.Counter(" + ".join(k for k, r in zip(KINDS, row) if r) or "none" for row in in_reach)
  outcome = {"succeeded": ok, "collided": hit, "timed out": timed_out(per)}
  tight = {f"{r:g}": {k: int((~way[:, i] & m).sum()) for k, m in outcome.items()} for i, r in enumerate(discs)}
  return {"run": run_dir, "area": area, "trials": int(len(hit)), "success": float(ok.mean()),
          "collided": int(hit.sum()), "success_goal_miss_max_m": float(miss.max()) if miss.size else None,
          "nearest": {k: int((nearest == i).sum()) for i, k in enumerate(KINDS)},
          "reach_m": {"non-belt": round(body_reach, 3), "any": round(robot_reach, 3)}, "in_reach": dict(reach),
          "outcomes": {k: int(m.sum()) for k, m in outcome.items()}, "no_way_round_for_disc_m": tight,
          "collided_distance_m": {k: [round(float(x), 3) for x in near[hit, i]] for i, k in enumerate(KINDS)}}


def main(argv: list[str] | None = None) -> int:
  p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  p.add_argument("runs", nargs="+", help="run folders with eval-nav-AREA.json reports")
  p.add_argument("--check-radius", type=float, default=0.8, help="m: a successful trial ends this near its goal")
  p.add_argument("--discs", default="0.5,0.62,0.75",
                 help="m, disc radii whose way round each layout is checked "
                 "(robot 1: 0.62 turning at rest, 0.75 its arm out)")
  p.add_argument("--out", help="JSON path")
  args = p.parse_args(argv)
  discs = tuple(float(x) for x in args.discs.split(","))
  rows = [r for run in args.runs for area in NAV_AREAS if (r := sites(run, f"nav/{area}", args.check_radius, discs))]
  for r in rows:
    print(f"{r['run']} {r['area']}: {r['collided']} of {r['trials']} trials collided; nearest to their end: "
          + ", ".join(f"{k} {n}" for k, n in r["nearest"].items()))
  total = {k: sum(r["nearest"][k] for r in rows) for k in KINDS}
  reach_all = dict(sum((collections.Counter(r["in_reach"]) for r in rows), collections.Counter()))
  print(f"all: {sum(r['collided'] for r in rows)} collisions; nearest: {total}")
  print(f"within reach of the collided robot (reach {rows[0]['reach_m'] if rows else '-'} m): {reach_all}")
  outcomes = {k: sum(r["outcomes"][k] for r in rows) for k in rows[0]["outcomes"]} if rows else {}
  tight = {d: {k: sum(r["no_way_round_for_disc_m"][d][k] for r in rows) for k in outcomes}
           for d in map("{:g}".format, discs)}
  for d, n in tight.items():
    print(f"no way round for a {d} m disc: " + ", ".join(f"{n[k]} of {outcomes[k]} {k}" for k in outcomes))
  if args.out:
    atomic.write_json(args.out, {**provenance(), "nearest_all": total, "in_reach_all": reach_all, "outcomes_all": outcomes,
                                 "no_way_round_all": tight,
                                 "rows": rows})
  return 0


if __name__ == "__main__":
  raise SystemExit(main())

"""Can the robot pass the navigation areas at all? A scripted controller that sees the whole state
and steers down the free-space distance's gradient (the shortest path around the wall obstacles
that keeps the task's clearance, scenes.geodesic, as the reward measures it; with
--floor-clearance, around the floor obstacles too), turning on the spot when the path turns
sharply, flippers held; on each scene of the tasks' evaluation suites, success
and collisions by the tasks' own rules. Prints a table and writes JSON with the device, command and
date; each row lists the trials that collided and those that timed out (mjx_tracks.metrics.timed_out:
neither reached, collided nor tipped over; files written before 2026-11-27 counted tip-overs among
them), by index: trial t is the same layout as trial t of every evaluation of that scene.

python scripts/analysis/nav_scripted.py --tasks nav-hard --out results/hard_tier/nav-scripted-cpu.json \
    [--scenes nav/hallway,nav/zigzag] [--trials 100] [--speed 0.5] [--floor-clearance 0.44] [--set KEY=VALUE ...]
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import sys

import jax
import jax.numpy as jnp
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
from mjx_tracks import atomic, compile_cache  # noqa: E402
from mjx_tracks.envs.config import load_config  # noqa: E402
from mjx_tracks.envs.task_env import TrackedRobotEnv  # noqa: E402
from mjx_tracks.metrics import timed_out  # noqa: E402
from mjx_tracks.sim.pose import chassis_rpy, wrap_angle  # noqa: E402
from scenes.navigation import WALL_OBSTACLES  # noqa: E402
from train.evaluation import EVAL_EPS, EVAL_SEED, scene_config, suite_scenes, trial_runner  # noqa: E402

STEER_GAIN = 2.0  # rad/s of yaw rate per rad of heading error
TURN_ON_SPOT = 0.6  # rad: a heading error beyond this stops the drive and turns in place


def path_length(core: TrackedRobotEnv, es, floor_clearance: float | None):
  """G(xy) (m): the task's free-space distance (around the wall obstacles), or with floor_clearance
  (m) the shortest path around the floor obstacles too, keeping that clearance from every box
  (NavScene.free_space_distance caps it as it caps its own, so that the area's gap stays open)."""
  if floor_clearance is None:
    return lambda xy: core.scene.free_space_distance(es.scene, xy)
  boxes = WALL_OBSTACLES + core.scene.floor_obstacles
  return lambda xy: core.scene.free_space_distance(es.scene, xy, boxes, floor_clearance)


def make_act(core: TrackedRobotEnv, speed: float, floor_clearance: float | None):
  """act(state) for a batch of env states: (v, w, front, rear) actions of the 4-DOF mode that follow
  -grad G, G the path length to the goal (m, path_length)."""
  c = core.controller

  def one(s):
    es = s.pipeline_state
    pos = es.data.qpos[0:3]
    grad = jax.grad(path_length(core, es, floor_clearance))(pos[:2])
    to_goal = es.scene.goal[:2] - pos[:2]
    down = jnp.where(jnp.all(jnp.isfinite(grad)) & (jnp.linalg.norm(grad) > 1e-6), -grad, to_goal)
    error = wrap_angle(jnp.arctan2(down[1], down[0]) - chassis_rpy(es.data.qpos)[2])
    v = jnp.where(jnp.abs(error) > TURN_ON_SPOT, 0.0, speed)
    w = jnp.clip(STEER_GAIN * error, -c.max_yaw_rate, c.max_yaw_rate)
    return c.encode(v, w, es.targets, es.targets)

  return lambda _params: jax.vmap(one)


def run(task: str, scene: str, speed: float, trials: int, overrides: list[str],
        floor_clearance: float | None) -> dict:
  """One scene of one task (with config overrides): the trials' mean figures."""
  task_cfg = load_config(task, overrides)
  core = TrackedRobotEnv(scene_config(task_cfg, scene))
  act = make_act(core, speed, floor_clearance)
  figs, _, _ = trial_runner(task_cfg, [scene], act, trials, EVAL_EPS, EVAL_SEED, observe=lambda s: s)(None, scene)
  mean = lambda k: round(float(np.mean(figs[k])), 3)  # noqa: E731
  return {"task": task, "overrides": overrides, "scene": scene, "speed_m_s": speed,
          "floor_clearance_m": floor_clearance, "trials": trials,
          **{k: mean(k) for k in ("success", "progress", "collided", "tipped_over", "length")},
          "collided_trials": np.flatnonzero(np.asarray(figs["collided"]) > 0).tolist(),  # indices: compare policies trial by trial
          "timed_out_trials": np.flatnonzero(timed_out(figs)).tolist()}


def main(argv: list[str] | None = None) -> int:
  p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  p.add_argument("--tasks", default="nav", help="navigation tasks, comma-separated")
  p.add_argument("--scenes", help="evaluation scenes, comma-separated (default: each task's suite)")
  p.add_argument("--trials", type=int, default=100)
  p.add_argument("--speed", type=float, default=0.5, help="m/s while the path runs ahead")
  p.add_argument("--floor-clearance", type=float, help="m: steer round the floor obstacles too, this far from "
                 "every box (default: the task's path, around the wall obstacles only; floor obstacles driven over)")
  p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="config override of the tasks")
  p.add_argument("--out", required=True)
  args = p.parse_args(argv)
  compile_cache.enable()
  rows = []
  for task in args.tasks.split(","):
    for scene in args.scenes.split(",") if args.scenes else suite_scenes(load_config(task, args.set)):
      rows.append(run(task, scene, args.speed, args.trials, args.set, args.floor_clearance))
      print(json.dumps(rows[-1]), flush=True)
  atomic.write_json(args.out, {
      "device": str(jax.devices()[0]), "machine": platform.machine(),
      "command": "python scripts/analysis/nav_scripted.py " + " ".join(sys.argv[1:] if argv is None else argv),
      "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"), "rows": rows})
  return 0


if __name__ == "__main__":
  sys.exit(main())

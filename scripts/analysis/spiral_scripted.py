"""Can the robot take the spiral staircases at all? A scripted controller that sees the whole state:
steering along a lane of the stairs (the centre line, or a radius offset from it), the stair
script's flipper rules and speed (mjx_tracks.tools.scripted), on each scene of the spiral tasks'
evaluation suites; success and tip-overs by the tasks' own rules. Prints a table and writes JSON
with the device, command and date; --gif DIR adds a GIF of trial 0 per task, lane and scene.

python scripts/analysis/spiral_scripted.py --out results/terrain/spiral-scripted.json [--trials 8]
    [--tasks spiral-up-hard,spiral-down-hard] [--scenes hardest] [--lanes 0,0.5]
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
from mjx_tracks import compile_cache  # noqa: E402
from mjx_tracks.envs.config import load_config  # noqa: E402
from mjx_tracks.envs.task_env import TrackedRobotEnv  # noqa: E402
from mjx_tracks.sim.control import INCREMENT  # noqa: E402
from mjx_tracks.sim.pose import chassis_rpy, wrap_angle  # noqa: E402
from mjx_tracks.tools.scripted import StairScript  # noqa: E402
from scenes.spiral import landing_angle  # noqa: E402
from train.evaluation import scene_config, suite_scenes, trial_runner  # noqa: E402

STEER_GAIN = 1.5  # rad/s of yaw rate per rad of heading error
LANE_GAIN = 0.8  # rad of heading correction per m off the lane, at most LANE_MAX
LANE_MAX = 0.6  # rad
LANES = (0.0, 0.5)  # m from the centre line (+: outward, where the treads are longer)


def desired_heading(xy, xi, goal, up: bool, lane: float):
  """Heading (rad) that follows the lane around the axis (0, radius), then makes for the goal point."""
  radius = xi[0]
  phi = jnp.arctan2(xy[0], radius - xy[1])  # angle around the axis, 0 at the first step
  off = jnp.hypot(xy[0], radius - xy[1]) - (radius + lane)  # m outside the lane
  correction = jnp.clip(LANE_GAIN * off, -LANE_MAX, LANE_MAX)
  along = phi + correction if up else phi - jnp.pi - correction
  past = phi > landing_angle(xi) if up else phi < 0.0  # on the landing (up) / before the stairs (down)
  to_goal = jnp.arctan2(goal[1] - xy[1], goal[0] - xy[0])
  return jnp.where(past, to_goal, along)


def make_act(core: TrackedRobotEnv, up: bool, lane: float):
  """act(state) for a batch of env states: (v, w, front, rear) actions of the 4-DOF mode."""
  c, robot = core.controller, core.sim.robot
  script = StairScript("up" if up else "down")
  front, rear = robot.joint_index("front")[0], robot.joint_index("rear")[0]
  lo, hi = c.v_range

  def one(s):
    es = s.pipeline_state
    rpy = chassis_rpy(es.data.qpos)
    speed, targets = script.command(robot, -rpy[1])
    heading = desired_heading(es.data.qpos[:2], es.scene.xi, es.scene.goal, up, lane)
    w = jnp.clip(STEER_GAIN * wrap_angle(heading - rpy[2]) / c.max_yaw_rate, -1.0, 1.0)
    joint = lambda i: jnp.clip((targets[i] - es.targets[i]) / INCREMENT, -1.0, 1.0)  # noqa: E731
    return jnp.stack([2.0 * (speed - lo) / (hi - lo) - 1.0, w, joint(front), joint(rear)])

  return lambda _params: jax.vmap(one)


def run(task: str, scene: str, lane: float, trials: int, gif: str | None) -> dict:
  """One scene of one task with one lane: the trials' mean figures."""
  task_cfg = load_config(task)
  cfg = scene_config(task_cfg, scene)
  core = TrackedRobotEnv(cfg)
  runner = trial_runner(task_cfg, [scene], make_act(core, cfg.scene.terrains[0] == "spiral_up", lane), trials, 1.0, 1,
                        record=bool(gif), observe=lambda s: s)
  figs, qpos, model = runner(None, scene)
  if gif:
    from mjx_tracks.tools.render import render_frames, write_video  # noqa: PLC0415
    shown = qpos[:int(figs["length"][0]) + 1]
    write_video(os.path.join(gif, f"{task}-{scene.replace('/', '-')}-lane{lane}.gif"), render_frames(model, shown),
                1 / cfg.control.period)
  return {"task": task, "scene": scene, "lane_m": lane, "trials": trials,
          **{k: round(float(np.mean(figs[k])), 3) for k in ("success", "progress", "tipped_over", "length")}}


def main(argv: list[str] | None = None) -> int:
  p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  p.add_argument("--out", required=True)
  p.add_argument("--trials", type=int, default=8)
  p.add_argument("--gif", help="a folder for GIFs of trial 0")
  p.add_argument("--tasks", default="spiral-up,spiral-down", help="spiral tasks, comma-separated")
  p.add_argument("--scenes", help="evaluation scenes, comma-separated (default: each task's suite)")
  p.add_argument("--lanes", default=",".join(map(str, LANES)), help="m from the centre line, comma-separated")
  args = p.parse_args(argv)
  compile_cache.enable()
  if args.gif:
    os.makedirs(args.gif, exist_ok=True)
  rows = []
  for task in args.tasks.split(","):
    for scene in args.scenes.split(",") if args.scenes else suite_scenes(load_config(task)):
      for lane in map(float, args.lanes.split(",")):
        rows.append(run(task, scene, lane, args.trials, args.gif))
        print(json.dumps(rows[-1]), flush=True)
  out = {"device": str(jax.devices()[0]), "machine": platform.machine(), "argv": sys.argv,
         "command": "python scripts/analysis/spiral_scripted.py " + " ".join(sys.argv[1:] if argv is None else argv),
         "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"), "rows": rows}
  with open(args.out, "w") as f:
    json.dump(out, f, indent=1)
  return 0


if __name__ == "__main__":
  sys.exit(main())

"""Drive one robot on one staircase by script or keyboard; write its trajectory and a summary.

python -m mjx_tracks.tools.drive --robot 1 --stairs 0.17,0.30,7 --direction up --seconds 20 \
    [--controller scripted|keyboard] [--out traj.json] [--video out.mp4]
"""

from __future__ import annotations

import argparse
import dataclasses
import functools
import sys
import time

import jax
import jax.numpy as jnp
import numpy as np

from mjx_tracks import atomic
from mjx_tracks.envs.config import default_config
from mjx_tracks.envs.rewards import goal_distance, goal_reached
from mjx_tracks.robots import get_robot
from mjx_tracks.sim.control import command_belt_speeds
from mjx_tracks.metrics import trajectory_success
from mjx_tracks.sim.pose import chassis_rpy, tipped_over
from mjx_tracks.sim.simulator import Simulator, staircase_simulator
from mjx_tracks.tools.scripted import StairScript
from scenes import staircase as sc


@dataclasses.dataclass(frozen=True)
class DriveSetup:
  """One drive: robot on one staircase, start pose from the direction."""

  sim: Simulator
  stairs: sc.Staircase
  direction: str  # "up" | "down"
  control_period: float  # s
  goal_tolerance: float  # m

  @property
  def substeps(self) -> int:
    return max(1, round(self.control_period / self.sim.physics.timestep))

  def model(self):
    return stairs_model(self.sim, self.stairs)

  def goal(self):
    """Goal point (m): past the top edge going up, before the first riser going down."""
    return stairs_goal(self.stairs, self.direction == "up")

  def initial_data(self):
    return start_data(self.sim, self.stairs, self.direction == "up")


def stairs_model(sim: Simulator, stairs: sc.Staircase):
  """The simulator's model with the staircase's step boxes."""
  return sim.with_boxes(*sc.step_boxes(stairs))


def stairs_goal(stairs: sc.Staircase, up) -> jax.Array:
  """The goal point (m) going up where up, else going down; up: a bool, or a bool array (the
  direction as data)."""
  return jnp.where(up, sc.ascent_goal(stairs), sc.descent_goal(stairs))


def start_data(sim: Simulator, stairs: sc.Staircase, up):
  """The robot at the ascent spawn where up, else at the descent spawn, its joints at 0; up as in
  stairs_goal."""
  (pos_up, yaw_up), (pos_down, yaw_down) = sc.ascent_spawn(stairs), sc.descent_spawn(stairs)
  return sim.init_data(jnp.where(up, pos_up, pos_down), jnp.where(up, yaw_up, yaw_down),
                       jnp.zeros(sim.layout.n_joints))


def parse_stairs(text: str) -> sc.Staircase:
  """'H,L,N' (riser m, tread m, steps) -> Staircase, with range checks."""
  try:
    h, l, n = text.split(",")
    h, l, n = float(h), float(l), int(n)
  except ValueError:
    raise SystemExit(f"error: --stairs must be H,L,N (riser m, tread m, steps), got {text!r}")
  (l_lo, l_hi), (h_lo, h_hi), (n_lo, n_hi) = sc.STAIR_LIMITS
  if not (h_lo <= h <= h_hi and l_lo <= l <= l_hi and n_lo <= n <= n_hi):
    raise SystemExit(f"error: --stairs out of range: need {h_lo} <= H <= {h_hi}, {l_lo} <= L <= {l_hi}, "
                     f"{n_lo} <= N <= {n_hi}; got H={h}, L={l}, N={n}")
  return sc.Staircase(jnp.float32(l), jnp.float32(h), jnp.int32(n))


CONTROLLERS = ("scripted", "full")  # StairScript; full belt speed with the joints held at 0


def scripted_rollouts(setup: DriveSetup, n_steps: int, controller: str = "scripted") -> np.ndarray:
  """One rollout of n_steps control periods per staircase of setup.stairs (fields with a batch axis
  B); returns qpos (B, n_steps + 1, nq). The robot stops at the goal. The direction is data: up and
  down run one program, compiled once per simulator, substeps, length and controller."""
  if controller not in CONTROLLERS:
    raise ValueError(f"controller must be one of {CONTROLLERS}, got {controller!r}")
  program = _rollouts_program(_Identity(setup.sim), setup.substeps, n_steps, controller)
  return np.asarray(program(setup.stairs, jnp.asarray(setup.direction == "up")))


class _Identity:
  """A cache key that is its object's identity (a Simulator holds arrays: it has no hash)."""

  def __init__(self, obj):
    self.obj = obj

  def __hash__(self):
    return id(self.obj)

  def __eq__(self, other):
    return isinstance(other, _Identity) and other.obj is self.obj


@functools.lru_cache(maxsize=8)
def _rollouts_program(sim_key: _Identity, substeps: int, n_steps: int, controller: str):
  """jit(vmap over staircases) of one drive: (stairs with a batch axis, up: bool) -> qpos."""
  sim = sim_key.obj
  robot, script = sim.robot, StairScript("up")  # its direction unused: command_either takes it as data

  def one(stairs: sc.Staircase, up: jax.Array) -> jax.Array:
    m, goal_x, ahead = stairs_model(sim, stairs), stairs_goal(stairs, up)[0], jnp.where(up, 1.0, -1.0)

    def control_step(d, _):
      if controller == "full":
        speed, targets = robot.max_speed, jnp.zeros(sim.layout.n_joints)
      else:
        speed, targets = script.command_either(robot, -chassis_rpy(d.qpos)[1], up)  # from the nose-up angle
      speed = jnp.where(ahead * (d.qpos[0] - goal_x) >= 0.0, 0.0, speed)  # stop at the goal (+x is up the stairs)
      belts = command_belt_speeds(speed, 0.0, robot.track_separation, robot.steering_efficiency,
                                  robot.max_speed)
      d = sim.advance(m, d, belts, targets, substeps)
      return d, d.qpos

    d0 = start_data(sim, stairs, up)
    _, qpos = jax.lax.scan(control_step, d0, None, length=n_steps)
    return jnp.concatenate([d0.qpos[None], qpos], axis=0)

  return jax.jit(jax.vmap(one, in_axes=(0, None)))


def scripted_rollout(setup: DriveSetup, n_steps: int) -> np.ndarray:
  """The scripted controller on setup's one staircase; qpos (n_steps + 1, nq)."""
  batch = jax.tree_util.tree_map(lambda x: jnp.asarray(x)[None], setup.stairs)
  return scripted_rollouts(dataclasses.replace(setup, stairs=batch), n_steps)[0]


def summarize(setup: DriveSetup, qpos: np.ndarray) -> dict:
  """Distance travelled, final height, max |pitch|, tipped over, goal reached (the tasks' rule)."""
  rpy = np.asarray(chassis_rpy(jnp.asarray(qpos)))
  tipped_flags = np.asarray(tipped_over(jnp.asarray(rpy)))
  tipped = bool(tipped_flags.any())
  xyz = qpos[:, :3]
  dist = goal_distance(jnp.asarray(xyz), setup.goal(), sc.GOAL_HALFWIDTH, setup.goal_tolerance)
  return {
      "distance_m": float(np.linalg.norm(np.diff(xyz, axis=0), axis=1).sum()),
      "final_height_m": float(xyz[-1, 2] - setup.sim.robot.spawn_height),
      "max_abs_pitch_rad": float(np.abs(rpy[:, 1]).max()),
      "tipped_over": tipped,
      "goal_reached": trajectory_success(np.asarray(goal_reached(dist)), tipped_flags),  # the tasks' success
  }


def trajectory_record(setup: DriveSetup, qpos: np.ndarray, summary: dict) -> dict:
  """JSON-ready trajectory: time, position, roll / pitch / yaw, joint angles, summary."""
  rpy = np.asarray(chassis_rpy(jnp.asarray(qpos)))
  joints = qpos[:, setup.sim.layout.joint_qpos]
  t = np.arange(len(qpos)) * setup.control_period
  return {
      "robot": setup.sim.robot.name,
      "stairs": {"riser_m": float(setup.stairs.riser), "tread_m": float(setup.stairs.tread),
                 "steps": int(setup.stairs.steps)},
      "direction": setup.direction,
      "control_period_s": setup.control_period,
      "joint_names": list(setup.sim.layout.joint_names),
      "t": t.tolist(), "x": qpos[:, 0].tolist(), "y": qpos[:, 1].tolist(),
      "z": qpos[:, 2].tolist(), "roll": rpy[:, 0].tolist(), "pitch": rpy[:, 1].tolist(),
      "yaw": rpy[:, 2].tolist(), "joints": joints.tolist(),
      "summary": summary,
  }


def main(argv: list[str] | None = None) -> int:
  p = argparse.ArgumentParser(prog="python -m mjx_tracks.tools.drive", description=__doc__.splitlines()[0])
  p.add_argument("--robot", default="1", help="1 (Jaguar with arm) or 2 (Absolem)")
  p.add_argument("--stairs", default="0.17,0.30,7", help="riser H (m), tread L (m), steps N")
  p.add_argument("--direction", choices=("up", "down"), default="up")
  p.add_argument("--seconds", type=float, default=20.0)
  p.add_argument("--controller", choices=("scripted", "keyboard"), default="scripted")
  p.add_argument("--control-period", type=float, default=0.1, help="s between commands")
  p.add_argument("--out", help="trajectory JSON path")
  p.add_argument("--video", help="MP4 path (needs the video extra)")
  args = p.parse_args(argv)
  try:
    robot = get_robot(args.robot)
  except KeyError as e:
    raise SystemExit(f"error: {e.args[0]}")
  if not 0 < args.seconds <= 600:
    raise SystemExit("error: --seconds must be in (0, 600]")
  from mjx_tracks import compile_cache  # noqa: PLC0415
  compile_cache.enable()
  defaults = default_config()
  setup = DriveSetup(staircase_simulator(robot, defaults.physics), parse_stairs(args.stairs), args.direction,
                     args.control_period, defaults.episode.goal_tolerance)
  n_steps = max(1, round(args.seconds / args.control_period))
  t0 = time.time()
  if args.controller == "scripted":
    print(f"compiling and simulating {args.seconds:g} s on {jax.default_backend()} ...", file=sys.stderr)
    qpos = scripted_rollout(setup, n_steps)
  else:
    from mjx_tracks.tools.teleop import keyboard_rollout  # noqa: PLC0415
    qpos = keyboard_rollout(setup, n_steps)
  summary = summarize(setup, qpos)
  if args.out:
    atomic.write_json(args.out, trajectory_record(setup, qpos, summary), indent=None)
  if args.video:
    from mjx_tracks.tools.render import render_frames, write_video  # noqa: PLC0415
    mj = setup.sim.c_model_with_boxes(*sc.step_boxes(setup.stairs))
    write_video(args.video, render_frames(mj, qpos), fps=1.0 / args.control_period)
  print(f"{robot.name} {args.direction} h={float(setup.stairs.riser):.2f} l={float(setup.stairs.tread):.2f} "
        f"n={int(setup.stairs.steps)}: distance {summary['distance_m']:.2f} m, final height "
        f"{summary['final_height_m']:.2f} m, max |pitch| {summary['max_abs_pitch_rad']:.2f} rad, "
        f"tipped over: {'yes' if summary['tipped_over'] else 'no'}, goal reached: "
        f"{'yes' if summary['goal_reached'] else 'no'} ({time.time() - t0:.1f} s wall)")
  return 0


if __name__ == "__main__":
  sys.exit(main())

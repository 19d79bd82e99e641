"""The spawn with flippers lowered (control.start_pose, start jitter): the chassis starts high enough
that no flipper starts inside the ground, against a hand-derived lift and the MuJoCo C engine's
contacts. (Before: a robot spawned with both pairs at -45 degrees started with its flipper tips
0.11 m in the floor and drove backwards under a forward command.)"""

import math

import jax.numpy as jnp
import mujoco
import numpy as np
import pytest

import mjx_tracks
from mjx_tracks.sim.simulator import SPAWN_CLEARANCE

HIDDEN = np.array([[-20.0, 0.0, -5.0]] * 2), np.array([[0.1, 0.1, 0.1]] * 2)  # the nav world's two wall obstacles, out of the way


def _deepest_ground_contact(env, qpos) -> float:
  """m: the most negative distance between a robot geom and the world's ground planes / walls in the
  C engine at qpos (0 where nothing touches)."""
  m = env.sim.c_model_with_boxes(*HIDDEN)
  d = mujoco.MjData(m)
  d.qpos[:] = np.asarray(qpos)
  mujoco.mj_forward(m, d)
  robot = np.asarray(m.geom_bodyid) > 0
  dists = [c.dist for c in d.contact[: d.ncon] if robot[c.geom1] != robot[c.geom2]]
  return min([0.0, *dists])


def test_lowered_flippers_lift_the_spawn_by_their_reach():
  env = mjx_tracks.load("nav")
  robot, sim = env.robot, env.sim
  n = len(robot.joint_names())
  down = np.zeros(n, np.float32)
  down[:4] = -math.pi / 4
  # jaguar: the tip capsule (end 0.23 m, radius 0.045 m) reaches 0.23 sin 45 deg + 0.045 = 0.2076 m below
  # the pivot, 0.1176 m beyond the track radius (0.09 m)
  assert robot.pose_lift(down) == pytest.approx(0.23 * math.sin(math.pi / 4) + 0.045 - 0.09, abs=1e-6)
  assert robot.pose_lift(np.zeros(n)) == 0.0 and robot.pose_lift(-down) == 0.0  # in line, raised
  assert float(robot.pose_lift(jnp.asarray(down), jnp)) == pytest.approx(float(robot.pose_lift(down)), abs=1e-6)
  pos, yaw = jnp.array([6.0, 0.0, 0.0]), jnp.float32(0.3)
  lifted = sim.init_data(pos, yaw, jnp.asarray(down)).qpos
  assert _deepest_ground_contact(env, lifted) > -1e-4  # the C engine: nothing starts inside the ground
  unlifted = np.asarray(lifted).copy()
  unlifted[2] = robot.spawn_height + SPAWN_CLEARANCE  # as before: 0.11 m into the floor
  assert _deepest_ground_contact(env, unlifted) == pytest.approx(-(robot.pose_lift(down) - SPAWN_CLEARANCE), abs=0.01)
  # one pair lowered: lifted by that pair's reach, the other pair's in-line reach is less
  front = np.where(np.arange(n) < 2, down, 0.0)
  assert robot.pose_lift(front) == pytest.approx(robot.pose_lift(down), abs=1e-6)
  assert _deepest_ground_contact(env, sim.init_data(pos, yaw, jnp.asarray(front)).qpos) > -1e-4

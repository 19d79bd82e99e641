"""Stairs: scripted climb and descent for both robots; random actions stay finite and in limits;
batched (vmap) and single stepping agree."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from mjx_tracks.envs.config import default_config
from mjx_tracks.sim.control import Controller
from mjx_tracks.sim.culling import culling_figures
from mjx_tracks.tools.drive import DriveSetup, scripted_rollout, summarize
from mjx_tracks.sim.pose import chassis_rpy
from scenes import staircase as sc

SEVEN_STEPS = sc.Staircase(jnp.float32(0.30), jnp.float32(0.17), jnp.int32(7))


@pytest.mark.slow
@pytest.mark.parametrize("robot_fixture", ["jaguar_stairs", "absolem_stairs"])
@pytest.mark.parametrize("direction", ["up", "down"])
def test_scripted_controller_negotiates_seven_steps(robot_fixture, direction, request):
  sim = request.getfixturevalue(robot_fixture)
  setup = DriveSetup(sim, SEVEN_STEPS, direction, control_period=0.1,
                     goal_tolerance=default_config().episode.goal_tolerance)
  qpos = scripted_rollout(setup, n_steps=150)  # 15 s
  s = summarize(setup, qpos)
  assert not s["tipped_over"]
  assert s["goal_reached"], s
  expected_height = 7 * 0.17 if direction == "up" else 0.0
  assert s["final_height_m"] == pytest.approx(expected_height, abs=0.05)
  _assert_culling_keeps_every_touch(setup, qpos)


def _assert_culling_keeps_every_touch(setup: DriveSetup, qpos: np.ndarray) -> None:
  """At every state of the drive, MuJoCo's C engine (which keeps every pair) finds no more touching
  contacts than physics.contact_slots keeps, and each belt-box pair it finds touching is among the
  physics.box_pairs pairs MJX tests (nearest bounding spheres first, as MJX ranks them)."""
  from train.bench.gate import culling_checks
  most, worst = figures = culling_figures(setup.sim, setup.stairs, qpos)
  checks = culling_checks(setup.sim.physics, figures, "drive")
  assert all(c.ok for c in checks), checks
  assert most >= 4 and worst >= 0  # the drive rests on its tracks and on the steps: the check sees contacts


def test_random_actions_on_stairs_stay_finite_and_within_limits(jaguar_stairs):
  """3,000 physics steps (300 control steps x 10, 30 s) of random 8-DOF increments, some NaN."""
  sim = jaguar_stairs
  ctl = Controller.create(sim.robot, "8dof", increments=True, v_range=(-1.0, 1.0))
  stairs = sc.Staircase(jnp.float32(0.35), jnp.float32(0.22), jnp.int32(7))
  m = sim.with_boxes(*sc.step_boxes(stairs))
  pos, yaw = sc.ascent_spawn(stairs)
  d0 = sim.init_data(pos, yaw, jnp.zeros(sim.layout.n_joints))

  def body(carry, key):
    d, targets = carry
    k1, k2 = jax.random.split(key)
    a = jax.random.uniform(k1, (ctl.action_size,), minval=-1.5, maxval=1.5)
    a = jnp.where(jax.random.uniform(k2, a.shape) < 0.02, jnp.nan, a)
    v, w, targets = ctl.decode(a, targets)
    d = sim.advance(m, d, ctl.belt_speeds(v, w), targets, 10)
    q = d.qpos[sim.layout.joint_qpos]
    return (d, targets), (jnp.all(jnp.isfinite(d.qpos)) & jnp.all(jnp.isfinite(d.qvel)), q)

  keys = jax.random.split(jax.random.PRNGKey(0), 300)
  _, (finite, joints) = jax.jit(lambda d: jax.lax.scan(body, (d, jnp.zeros(6)), keys))(d0)
  assert bool(np.all(finite))
  lim = sim.layout.joint_limits
  tol = 0.05  # rad, soft limit constraints may penetrate a little
  assert np.all(np.asarray(joints) >= lim[:, 0] - tol) and np.all(np.asarray(joints) <= lim[:, 1] + tol)


def test_batched_and_single_steps_agree(jaguar_stairs):
  sim = jaguar_stairs
  treads = jnp.array([0.35, 0.40, 0.52])
  risers = jnp.array([0.12, 0.17, 0.22])
  steps = jnp.array([1, 4, 7])
  belts = jnp.array([[0.3] * 6, [0.5] * 6, [-0.2, 0.2, -0.2, 0.2, -0.2, 0.2]])
  targets = jnp.array([[0.5, 0.5, 0, 0, 0.3, 0], [0, 0, -0.5, -0.5, 0, 1.0], [0.2] * 6])

  def run(l, h, n, u, t):
    stairs = sc.Staircase(l, h, n)
    m = sim.with_boxes(*sc.step_boxes(stairs))
    pos, yaw = sc.ascent_spawn(stairs)
    d = sim.init_data(pos + jnp.array([0.6, 0, 0]), yaw, jnp.zeros(6))
    return sim.advance(m, d, u, t, 20).qpos

  fn = jax.jit(run)
  batched = jax.jit(jax.vmap(run))(treads, risers, steps, belts, targets)
  for i in range(3):
    single = fn(treads[i], risers[i], steps[i], belts[i], targets[i])
    np.testing.assert_allclose(np.asarray(batched[i]), np.asarray(single), atol=2e-4)
  assert not np.allclose(np.asarray(batched[0]), np.asarray(batched[1]))
  assert np.all(np.isfinite(np.asarray(chassis_rpy(batched))))

"""Track-contact model against hand-derived cases: flat speed, yaw rate, incline hold, belt direction."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from mjx_tracks.sim.control import command_belt_speeds
from mjx_tracks.sim.pose import chassis_rpy
from mjx_tracks.robots import get_robot
from mjx_tracks.sim import mjx_private
from mjx_tracks.sim.simulator import Simulator
from scenes.world import world_geom_attrs
from scenes import staircase as sc

SUBSTEPS = 25  # 0.25 s per call at dt = 0.01 s


@pytest.fixture(scope="module")
def flat(jaguar_stairs):
  """(simulator, flat-ground model, jitted 0.25 s advance)."""
  sim = jaguar_stairs
  m = sim.with_boxes(*sc.step_boxes(sc.Staircase(jnp.float32(0.3), jnp.float32(0.17), jnp.int32(0))))
  adv = jax.jit(lambda d, belts: sim.advance(m, d, belts, jnp.zeros(sim.layout.n_joints), SUBSTEPS))
  return sim, m, adv


def _run(adv, d, belts, n):
  out = []
  for _ in range(n):
    d = adv(d, belts)
    out.append(np.asarray(d.qpos))
  return d, np.stack(out)


def test_flat_ground_speed_matches_belt_speed(flat):
  sim, _, adv = flat
  r = sim.robot
  belts = command_belt_speeds(0.5, 0.0, r.track_separation, r.steering_efficiency, r.max_speed)
  d0 = sim.init_data(jnp.zeros(3), jnp.float32(0.0), jnp.zeros(sim.layout.n_joints))
  _, q = _run(adv, d0, belts, 12)  # 3 s
  speed = (q[-1, 0] - q[3, 0]) / (8 * 0.25)  # steady state over the last 2 s
  assert speed == pytest.approx(0.5, rel=0.05)
  assert abs(q[-1, 1]) < 0.02  # m, no lateral drift


def test_turn_in_place_yaw_rate_matches_steering_formula(flat):
  sim, _, adv = flat
  r = sim.robot
  belts = command_belt_speeds(0.0, 0.5, r.track_separation, r.steering_efficiency, r.max_speed)
  expected = r.steering_efficiency * float(belts[1] - belts[0]) / r.track_separation
  assert expected == pytest.approx(0.5, rel=1e-5)  # the mapping inverts the formula
  d0 = sim.init_data(jnp.zeros(3), jnp.float32(0.0), jnp.zeros(sim.layout.n_joints))
  _, q = _run(adv, d0, belts, 8)
  yaw = np.unwrap(np.asarray(chassis_rpy(jnp.asarray(q)))[:, 2])
  rate = (yaw[-1] - yaw[3]) / (4 * 0.25)
  assert rate == pytest.approx(expected, rel=0.10)
  assert np.linalg.norm(q[-1, :2]) < 0.05  # m, turns in place


def test_belt_bottom_moves_backward_and_front_end_down(flat):
  """Belt surface velocity u (y x r): backward under the track, downward on its front roller."""
  from mjx_tracks.sim.tracks import contact_belt_velocity
  sim, m, adv = flat
  d = sim.init_data(jnp.zeros(3), jnp.float32(0.0), jnp.zeros(sim.layout.n_joints))
  d = adv(d, jnp.zeros(6))
  d = jax.jit(lambda d: jax.tree_util.tree_map(lambda x: x, d))(d)
  from mujoco import mjx
  d = jax.jit(mjx.forward)(m, d)  # jitted: op by op, MJX takes a minute on a CPU
  on_belt, _, u_dir, _ = jax.jit(lambda m, d: contact_belt_velocity(m, d, sim.tracks, jnp.ones(6)))(m, d)
  c = mjx_private.contacts(d)
  touching = np.asarray(on_belt & (c.dist < 0))
  assert touching.sum() >= 4  # both side tracks rest on the floor at both ends
  np.testing.assert_allclose(np.asarray(u_dir)[touching], np.tile([-1.0, 0, 0], (touching.sum(), 1)),
                             atol=1e-3)


def _incline_world(angle: float) -> str:
  n = (-math.sin(angle), 0.0, math.cos(angle))
  return (f'<geom name="slope" type="plane" size="0 0 1" zaxis="{n[0]} {n[1]} {n[2]}" '
          f'{world_geom_attrs()}/>')


def test_zero_command_holds_on_20_degree_incline(default_physics):
  angle = math.radians(20)
  sim = Simulator.create(get_robot(1), _incline_world(angle), default_physics)
  nj = sim.layout.n_joints
  d = sim.init_data(jnp.zeros(3), jnp.float32(0.0), jnp.zeros(nj))
  normal = jnp.array([-math.sin(angle), 0.0, math.cos(angle)])
  quat = jnp.array([math.cos(-angle / 2), 0.0, math.sin(-angle / 2), 0.0])  # nose up 20 deg
  d = d.replace(qpos=d.qpos.at[:3].set((sim.robot.spawn_height + 0.002) * normal).at[3:7].set(quat))
  adv = jax.jit(lambda d: sim.advance(sim.model, d, jnp.zeros(6), jnp.zeros(nj), SUBSTEPS))
  for _ in range(4):  # settle 1 s
    d = adv(d)
  start = np.asarray(d.qpos[:3])
  for _ in range(20):  # 5 s
    d = adv(d)
  creep = np.linalg.norm(np.asarray(d.qpos[:3]) - start)
  assert creep < 0.01, f"crept {creep:.4f} m in 5 s"

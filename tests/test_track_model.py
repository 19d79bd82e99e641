"""Track-contact model against hand-derived cases: flat speed, yaw rate and incline hold (the physics
gate's oracles, train/bench/gate.py, under the default physics), belt direction."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from mjx_tracks.sim.control import command_belt_speeds
from mjx_tracks.robots import get_robot
from mjx_tracks.sim import mjx_private
from scenes import staircase as sc

SUBSTEPS = 25  # 0.25 s per call at dt = 0.01 s


@pytest.fixture(scope="module")
def flat(jaguar_stairs):
  """(simulator, flat-ground model, jitted 0.25 s advance)."""
  sim = jaguar_stairs
  m = sim.with_boxes(*sc.step_boxes(sc.Staircase(jnp.float32(0.3), jnp.float32(0.17), jnp.int32(0))))
  adv = jax.jit(lambda d, belts: sim.advance(m, d, belts, jnp.zeros(sim.layout.n_joints), SUBSTEPS))
  return sim, m, adv


def test_flat_ground_speed_drift_and_yaw_rate_pass_the_physics_gate(default_physics):
  """Speed at 0.5 m/s commanded (5 %), lateral drift (0.02 m) and yaw rate at 0.5 rad/s against the
  steering formula (10 %): the gate's oracles (train/bench/gate.py), under the default physics."""
  from train.bench import gate
  r = get_robot(1)
  belts = command_belt_speeds(0.0, 0.5, r.track_separation, r.steering_efficiency, r.max_speed)
  assert r.steering_efficiency * float(belts[1] - belts[0]) / r.track_separation == pytest.approx(0.5, rel=1e-5)
  checks = gate.flat_checks(default_physics)
  assert [c.name for c in checks] == ["flat speed error", "flat lateral drift", "yaw rate error", "turn-in-place drift"]
  assert all(c.ok for c in checks), checks


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


def test_zero_command_holds_on_20_degree_incline(default_physics):
  """Creep with the belts stopped on a 20-degree incline, nose up: the gate's oracle (<= 0.01 m in 5 s)."""
  from train.bench import gate
  (check,) = gate.incline_check(default_physics)
  assert check.ok, f"crept {check.value:.4f} m in 5 s"

"""The one module on MJX's private API: its step equals `mjx.step` bit for bit where the track model
has nothing to do, and models that break its assumptions are refused at compile time."""

import dataclasses

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
import pytest
from mujoco import mjx

from mjx_tracks.robots import get_robot
from mjx_tracks.sim import mjx_private
from mjx_tracks.sim.physics import build_mjcf
from mjx_tracks.sim.simulator import step_with_tracks

SUBSTEPS = 20


def _resting(sim):
  """Robot 1 on the floor, servos driving the flippers and arm away from their rest angles."""
  targets = jnp.asarray(np.linspace(-0.4, 0.4, sim.layout.n_joints), jnp.float32)
  d = sim.init_data(jnp.zeros(3), jnp.float32(0.3), jnp.zeros(sim.layout.n_joints))
  return d.replace(ctrl=targets)


def _run(step_fn, m, d):
  return jax.jit(lambda d: jax.lax.fori_loop(0, SUBSTEPS, lambda _, x: step_fn(m, x), d))(d)


@pytest.fixture(scope="module")
def reference(jaguar_stairs):
  m = jaguar_stairs.model
  return _run(mjx.step, m, _resting(jaguar_stairs))


def test_step_with_noop_hooks_equals_mjx_step(jaguar_stairs, reference):
  m = jaguar_stairs.model
  noop = lambda m, d: mjx_private.step(m, d, lambda m, d: (d, None),
                                       lambda m, d, _: jnp.zeros(mjx_private.efc_rows(d)))
  ours = _run(noop, m, _resting(jaguar_stairs))
  assert int(np.asarray(mjx_private.contacts(ours).dist < 0).sum()) > 0  # the robot stands on contacts
  np.testing.assert_array_equal(np.asarray(ours.qpos), np.asarray(reference.qpos))
  np.testing.assert_array_equal(np.asarray(ours.qvel), np.asarray(reference.qvel))


def test_track_model_without_belt_contacts_equals_mjx_step(jaguar_stairs, reference):
  """No geom is a belt: the contacts stay MuJoCo's own and the step is mjx.step, even with belts
  commanded to move."""
  sim = jaguar_stairs
  no_belts = dataclasses.replace(sim.tracks, geom_belt=np.full_like(sim.tracks.geom_belt, -1))
  belts = jnp.full(6, 0.8)
  ours = _run(lambda m, d: step_with_tracks(m, d, no_belts, belts), sim.model, _resting(sim))
  np.testing.assert_array_equal(np.asarray(ours.qpos), np.asarray(reference.qpos))
  np.testing.assert_array_equal(np.asarray(ours.qvel), np.asarray(reference.qvel))


@pytest.mark.parametrize("edit,message", [
    (lambda x: x.replace('integrator="implicitfast"', 'integrator="Euler"'), "implicitfast"),
    (lambda x: x.replace('cone="pyramidal"', 'cone="elliptic"'), "pyramidal"),
    (lambda x: x.replace("</mujoco>", '<sensor><accelerometer site="imu"/></sensor></mujoco>'), "sensor"),
    (lambda x: x.replace('condim="3" material="world"', 'condim="6" material="world"', 1), "condim 3"),
])
def test_models_breaking_the_step_assumptions_are_refused(default_physics, edit, message):
  from scenes import staircase
  xml = build_mjcf(get_robot(1), staircase.world_xml(2), default_physics)
  mujoco.MjModel.from_xml_string(xml)  # the unedited model compiles and passes
  mjx_private.check_model(mujoco.MjModel.from_xml_string(xml))
  with pytest.raises(ValueError, match=message):
    mjx_private.check_model(mujoco.MjModel.from_xml_string(edit(xml)))


@pytest.fixture(scope="module")
def solver_inputs(jaguar_stairs, reference):
  """Robot 1 spawned (just above the floor) and standing on its contacts after the reference's
  substeps at 0-3x its velocity there, each run through mjx.forward: the inputs of a constraint
  solve (its Jacobian, reference accelerations, warm start). MJX's solver converges after 1, 2, 3,
  4 and 4 of its 4 Newton passes on them (mujoco-mjx 3.17.0)."""
  m = jaguar_stairs.model
  batch = [_resting(jaguar_stairs)] + [reference.replace(qvel=k * reference.qvel) for k in (0.0, 1.0, 2.0, 3.0)]
  return jax.jit(jax.vmap(lambda d: mjx.forward(m, d)))(jax.tree.map(lambda *x: jnp.stack(x), *batch))


def test_solve_equals_mjx_solver_alone_and_batched(jaguar_stairs, solver_inputs):
  """The fixed-length loop gives MJX's solver.solve's accelerations and forces bit for bit, for one
  robot and for a batch whose robots converge after different numbers of passes (vmap runs MJX's
  while loop until the last one has)."""
  from mujoco.mjx._src import solver
  m = jaguar_stairs.model
  fields = lambda d: (d.qacc, d.qfrc_constraint, d._impl.efc_force)
  ours = jax.jit(jax.vmap(lambda d: fields(mjx_private.solve(m, d))))(solver_inputs)
  theirs = jax.jit(jax.vmap(lambda d: fields(solver.solve(m, d))))(solver_inputs)
  one = jax.tree.map(lambda x: x[1], solver_inputs)  # converged after 2 passes
  ours_one = jax.jit(lambda d: fields(mjx_private.solve(m, d)))(one)
  theirs_one = jax.jit(lambda d: fields(solver.solve(m, d)))(one)
  for a, b in zip(ours + ours_one, theirs + theirs_one):
    np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
  assert float(np.abs(np.asarray(ours[2])).max()) > 0  # the robots stand on contacts

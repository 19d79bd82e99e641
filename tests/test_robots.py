"""Robot models built from their constants: masses, limits, collision filtering, sensor sites."""

import dataclasses

import mujoco
import numpy as np
import pytest

from mjx_tracks.robots import get_robot
from scenes.world import ROBOT_CONTYPE


@pytest.mark.parametrize("key,mass,has_arm", [("1", 22.2, True), ("2", 29.0, False)])
def test_model_mass_and_joints(key, mass, has_arm, request):
  sim = request.getfixturevalue("jaguar_stairs" if key == "1" else "absolem_stairs")
  m = sim.mj_model
  assert m.body_subtreemass[sim.layout.chassis_body] == pytest.approx(mass, abs=0.01)
  assert sim.robot.total_mass() == pytest.approx(mass, abs=0.01)
  assert sim.layout.n_joints == (6 if has_arm else 4)
  np.testing.assert_allclose(m.jnt_range[[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, n)
                                          for n in sim.robot.joint_names()]],
                             sim.robot.joint_limits(), atol=1e-6)
  assert (sim.layout.geom_belt >= 0).sum() == 2 + 2 * 4  # 2 side tracks + 2 capsules per flipper


def test_robot_parts_never_collide_with_each_other(jaguar_stairs):
  m = jaguar_stairs.mj_model
  robot = np.nonzero(m.geom_bodyid != 0)[0]
  for a in robot:
    for b in robot:
      mask = (m.geom_contype[a] & m.geom_conaffinity[b]) | (m.geom_contype[b] & m.geom_conaffinity[a])
      assert mask == 0
  assert (m.geom_contype[robot] & ROBOT_CONTYPE).any()


def test_camera_axis_meets_the_floor_where_its_height_and_pitch_say(jaguar_stairs):
  """A ray along the depth camera's axis (mj_ray) hits the floor at z_cam / sin(pitch), and the
  rendering camera coincides with the site the beams are cast from."""
  m, lay = jaguar_stairs.mj_model, jaguar_stairs.layout
  d = mujoco.MjData(m)
  mujoco.mj_forward(m, d)
  site_rot = d.site_xmat[lay.camera_site].reshape(3, 3)
  axis = -site_rot[:, 2]  # cameras look along -z
  origin = d.site_xpos[lay.camera_site]
  dist = mujoco.mj_ray(m, d, origin, axis, np.array([1, 0, 0, 0, 0, 0], np.uint8), 1, -1, np.zeros(1, np.int32))
  pitch = jaguar_stairs.robot.camera_pitch
  assert dist == pytest.approx(origin[2] / np.sin(pitch), rel=1e-3)
  cam = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_CAMERA, "depth_camera")
  np.testing.assert_allclose(d.cam_xpos[cam], origin, atol=1e-9)
  np.testing.assert_allclose(d.cam_xmat[cam].reshape(3, 3), site_rot, atol=1e-9)


def test_bad_physics_config_fails_clearly(default_physics):
  from mjx_tracks.sim.physics import compile_model
  with pytest.raises(ValueError, match="timestep"):
    compile_model(get_robot(1), "", dataclasses.replace(default_physics, timestep=0.5))
  for name in ("contact_slots", "box_pairs"):
    for bad in (0, -2):
      with pytest.raises(ValueError, match=f"physics.{name}: must be -1"):
        compile_model(get_robot(1), "", dataclasses.replace(default_physics, **{name: bad}))


def test_contact_limits_become_mjx_numerics_and_its_contact_slots(default_physics):
  """contact_slots / box_pairs become MJX's max_contact_points / max_geom_pairs numerics (MJX then
  keeps that many contact slots); -1 writes none, and MJX keeps a slot for every possible contact."""
  import jax.numpy as jnp
  from mjx_tracks.sim import mjx_private
  from mjx_tracks.sim.simulator import staircase_simulator

  def slots(**limits):
    sim = staircase_simulator(get_robot(1), dataclasses.replace(default_physics, **limits))
    m = sim.mj_model
    numerics = {m.numeric(i).name: float(m.numeric(i).data[0]) for i in range(m.nnumeric)}
    d = sim.init_data(jnp.zeros(3), jnp.float32(0.0))
    return numerics, mjx_private.contacts(d).dist.shape[0]

  assert slots(contact_slots=7, box_pairs=5) == ({"max_contact_points": 7.0, "max_geom_pairs": 5.0}, 7)
  assert slots(contact_slots=-1, box_pairs=-1) == ({}, 220)  # 3 planes x 11 belts x 2 + 7 boxes x 11 x 2

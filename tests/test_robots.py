"""Robot models built from their constants: masses, limits, collision filtering, sensor sites."""

import mujoco
import numpy as np
import pytest

from mjx_tracks.sim.physics import PhysicsConfig
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


def test_sensor_sites_where_the_reference_puts_them(jaguar_stairs):
  m = jaguar_stairs.mj_model
  np.testing.assert_allclose(m.site_pos[jaguar_stairs.layout.camera_site], (0.195, 0.1, 0.295))
  d = mujoco.MjData(m)
  mujoco.mj_forward(m, d)
  forward = -d.site_xmat[jaguar_stairs.layout.camera_site].reshape(3, 3)[:, 2]  # camera looks along -z
  assert np.degrees(np.arcsin(-forward[2])) == pytest.approx(np.degrees(0.46), abs=0.1)
  assert forward[0] > 0.8


def test_bad_physics_config_fails_clearly():
  from mjx_tracks.sim.physics import compile_model
  with pytest.raises(ValueError, match="timestep"):
    compile_model(get_robot(1), "", PhysicsConfig(timestep=0.5))
  with pytest.raises(KeyError, match="unknown robot"):
    get_robot(3)

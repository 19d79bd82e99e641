"""The 2D laser scan: MJX rays against MuJoCo's C engine (mujoco.mj_ray) in navigation areas."""

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
import pytest
from mujoco import mjx

import mjx_tracks
from mjx_tracks.envs.scan import ScanLayout, scan_ranges

GEOMGROUP = np.array([1, 0, 0, 0, 0, 0], np.uint8)  # the world group, as beams.RAY_GROUPS


@pytest.fixture(scope="module")
def nav_env():
  return mjx_tracks.load("nav")


def _pose(rng, x, y):
  """Chassis qpos[0:7] at (x, y) m, 0.09 m up (its track axis on the floor), any yaw, tilted a little."""
  quat = np.zeros(4)
  mujoco.mju_euler2Quat(quat, np.array([rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1), rng.uniform(-np.pi, np.pi)]), "xyz")
  return np.concatenate([[x, y, 0.09], quat])


def test_scan_reads_mj_ray_distances_capped_at_its_range(nav_env):
  layout = ScanLayout(24, 4.0, nav_env.robot.lidar_pos)
  sim, body = nav_env.sim, nav_env.sim.layout.chassis_body

  @jax.jit
  def mjx_scan(key, root):
    s = nav_env.scene.sample(key, jnp.float32(1.0))
    m = sim.with_boxes(s.box_pos, s.box_size)
    d = sim.init_data(jnp.zeros(3), jnp.float32(0.0), jnp.zeros(sim.layout.n_joints))
    d = mjx.kinematics(m, d.replace(qpos=d.qpos.at[:7].set(root)))
    return s, scan_ranges(layout, m, d, body)

  rng = np.random.default_rng(0)
  capped = near = 0
  for trial in range(5):  # spawn areas, the obstacle area, the goal area
    root = _pose(rng, rng.uniform(0.8, 11.2), rng.uniform(-4.2, 4.2))
    s, ranges = mjx_scan(jax.random.PRNGKey(trial), jnp.asarray(root, jnp.float32))
    c = sim.c_model_with_boxes(s.box_pos, s.box_size)
    data = mujoco.MjData(c)
    data.qpos[:7] = root
    mujoco.mj_forward(c, data)
    rot = data.xmat[body].reshape(3, 3)
    origin = data.xpos[body] + rot @ np.array(nav_env.robot.lidar_pos)
    oracle = []
    for k in range(24):  # ray k at yaw 2 pi k / 24 in the chassis frame, written out here
      a = 2 * np.pi * k / 24
      dist = mujoco.mj_ray(c, data, origin, rot @ np.array([np.cos(a), np.sin(a), 0.0]), GEOMGROUP, 1, -1,
                           np.zeros(1, np.int32))
      oracle.append(dist if 0 <= dist <= 4.0 else 4.0)
    np.testing.assert_allclose(np.asarray(ranges), oracle, atol=2e-3)
    capped += int(np.sum(np.array(oracle) == 4.0))
    near += int(np.sum(np.array(oracle) < 4.0))
  assert capped > 5 and near > 20  # both cases were checked


def test_scan_noise_loses_rays_with_their_probability(nav_env):
  layout = ScanLayout(360, 30.0, nav_env.robot.lidar_pos)  # 30 m: every ray of the closed area hits a wall
  s = nav_env.scene.sample(jax.random.PRNGKey(0), jnp.float32(0.0))
  m = nav_env.sim.with_boxes(s.box_pos, s.box_size)
  d = nav_env.sim.init_data(s.spawn_pos, s.spawn_yaw, jnp.zeros(nav_env.sim.layout.n_joints))
  d = mjx.kinematics(m, d)
  run = jax.jit(lambda k, r, h: scan_ranges(layout, m, d, nav_env.sim.layout.chassis_body, k, r, h))
  exact = np.asarray(run(jax.random.PRNGKey(1), 0.0, 0.0))
  assert (exact < 30.0).all()
  lost = np.mean([np.asarray(run(jax.random.PRNGKey(k), 0.0, 0.2)) == 30.0 for k in range(10)])
  assert abs(lost - 0.2) < 3 * np.sqrt(0.2 * 0.8 / 3600)  # binomial, 3,600 rays
  noisy = np.asarray(run(jax.random.PRNGKey(2), 0.05, 0.0))
  rel = noisy / exact - 1
  assert abs(rel.std() - 0.05) < 0.01 and abs(rel.mean()) < 0.01  # x (1 + N(0, 0.05))


def test_a_task_observing_the_scan_sees_it_in_its_observation():
  env = mjx_tracks.load("nav", ["observation.parts=[heading, scan]", "observation.scan_rays=8"])
  assert env.part_sizes == {"heading": 1, "scan": 8} and env.observation_size == 9
  state = jax.jit(env.reset)(jax.random.PRNGKey(4))
  ranges = np.asarray(state.obs[1:])
  assert ranges.min() > 0.3 and ranges.max() <= env.cfg.observation.scan_range  # no robot part seen

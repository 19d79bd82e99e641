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


RINGS = (0.0, 0.45, 0.28)  # rad down: horizontal, and meeting flat floor ~0.6 m and ~1.0 m away (robot 1)


def test_scan_rings_read_mj_ray_distances_capped_at_its_range():
  env = mjx_tracks.load("nav-obstacles")
  layout = ScanLayout(24, 4.0, env.robot.lidar_pos, RINGS)
  sim, body = env.sim, env.sim.layout.chassis_body
  sample = jax.jit(lambda key: env.scene.sample(key, jnp.float32(1.0)))

  @jax.jit
  def mjx_scan(s, root):
    m = sim.with_boxes(s.box_pos, s.box_size)
    d = sim.init_data(jnp.zeros(3), jnp.float32(0.0), jnp.zeros(sim.layout.n_joints))
    return scan_ranges(layout, m, mjx.kinematics(m, d.replace(qpos=d.qpos.at[:7].set(root))), body)

  rng = np.random.default_rng(0)
  capped = near = on_floor_box = 0
  floor_boxes = set(sim.layout.scene_boxes[2:].tolist())  # nav's floor obstacles follow its 2 wall obstacles
  for trial in range(5):  # beside a floor obstacle of each scene, at any yaw
    s = sample(jax.random.PRNGKey(trial))
    centre, a = np.asarray(s.box_pos[2 + trial, :2]), rng.uniform(-np.pi, np.pi)
    root = _pose(rng, *(centre + 0.8 * np.array([np.cos(a), np.sin(a)])))
    ranges = mjx_scan(s, jnp.asarray(root, jnp.float32))
    c = sim.c_model_with_boxes(s.box_pos, s.box_size)
    data = mujoco.MjData(c)
    data.qpos[:7] = root
    mujoco.mj_forward(c, data)
    rot = data.xmat[body].reshape(3, 3)
    origin = data.xpos[body] + rot @ np.array(env.robot.lidar_pos)
    oracle = []
    for p in RINGS:  # ray j 24 + k: ring j, yaw 2 pi k / 24 in the chassis frame, pitched down p; written out here
      for k in range(24):
        a, hit = 2 * np.pi * k / 24, np.zeros(1, np.int32)
        dist = mujoco.mj_ray(c, data, origin, rot @ np.array([np.cos(a) * np.cos(p), np.sin(a) * np.cos(p), -np.sin(p)]),
                             GEOMGROUP, 1, -1, hit)
        oracle.append(dist if 0 <= dist <= 4.0 else 4.0)
        on_floor_box += int(dist <= 4.0 and hit[0] in floor_boxes)
    np.testing.assert_allclose(np.asarray(ranges), oracle, atol=2e-3)
    capped += int(np.sum(np.array(oracle) == 4.0))
    near += int(np.sum(np.array(oracle) < 4.0))
  assert capped > 5 and near > 20 and on_floor_box > 5  # every case was checked


def test_a_pitched_ring_reads_the_floor_and_the_top_of_a_box_the_horizontal_ring_passes_over(nav_env):
  """Chassis level at (5, 0) facing +x, its scanner h = z + lidar z above the floor: a ring pitched
  down p reads h / sin p on bare floor; a 0.1 m box spanning x in [5.1, 6.1] under the forward ray
  is met on its top, (h - 0.1) / sin p away, while the horizontal ring passes over it."""
  sim, body, lidar = nav_env.sim, nav_env.sim.layout.chassis_body, nav_env.robot.lidar_pos
  layout = ScanLayout(4, 4.0, lidar, (0.0, 0.45))  # forward, left, back, right; horizontal then 0.45 rad down
  far = [[-50.0, -50.0, -5.0], [-60.0, -60.0, -5.0]]  # the area's two boxes put away, then one brought back
  low_box = ([[5.6, 0.0, 0.05], far[1]], [[0.5, 0.3, 0.05], [0.1, 0.1, 0.1]])  # centre, half-sizes (m)

  @jax.jit
  def scan(box_pos, box_size):
    m = sim.with_boxes(box_pos, box_size)
    d = sim.init_data(jnp.zeros(3), jnp.float32(0.0), jnp.zeros(sim.layout.n_joints))
    d = d.replace(qpos=d.qpos.at[:7].set(jnp.array([5.0 - lidar[0], 0.0, 0.09, 1.0, 0.0, 0.0, 0.0])))
    return scan_ranges(layout, m, mjx.kinematics(m, d), body)

  h = 0.09 + lidar[2]  # m, the scanner above the floor
  bare = np.asarray(scan(jnp.asarray(far), jnp.full((2, 3), 0.1)))
  np.testing.assert_allclose(bare[4:], h / np.sin(0.45), rtol=1e-4)  # each pitched ray meets the floor
  boxed = np.asarray(scan(jnp.asarray(low_box[0]), jnp.asarray(low_box[1])))
  np.testing.assert_allclose(boxed[4], (h - 0.1) / np.sin(0.45), rtol=1e-4)  # forward: the box's top
  np.testing.assert_allclose(boxed[5:], bare[5:], rtol=1e-5)  # the other pitched rays still meet the floor
  np.testing.assert_allclose(boxed[:4], bare[:4], rtol=1e-5)  # the horizontal ring passes over the box


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

"""Depth beams: MJX ray casting against mujoco.mj_ray on the CPU for random robot poses."""

import dataclasses

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
import pytest

from mjx_tracks.envs.beams import BeamLayout, cast
from mjx_tracks.envs.config import default_config
from mjx_tracks.envs.task_env import make_scene
from mjx_tracks.sim.simulator import Simulator

LAYOUT = BeamLayout.create(1.2, (640, 480), 60, 12, 10, (2, 2), (0.2, 1.5), 8.0)


def _stairs(**kw):
  """The default staircase scene, sampled uniformly, with scene-section overrides."""
  return make_scene(dataclasses.replace(default_config().scene, sampler="uniform", **kw))


def _random_pose(rng):
  """Chassis position near the stairs, random yaw / small roll and pitch (qpos[0:7])."""
  pos = [rng.uniform(-1.5, 2.0), rng.uniform(-0.6, 0.6), rng.uniform(0.1, 1.0)]
  r, p, y = rng.uniform(-0.3, 0.3), rng.uniform(-0.5, 0.5), rng.uniform(-np.pi, np.pi)
  quat = np.zeros(4)
  mujoco.mju_euler2Quat(quat, np.array([r, p, y]), "xyz")
  return np.concatenate([pos, quat])


def test_beam_rays_match_mj_ray_for_random_poses(jaguar_stairs):
  sim: Simulator = jaguar_stairs
  scene = _stairs()
  rng = np.random.default_rng(0)

  @jax.jit
  def mjx_depth(key, root):
    s = scene.sample(key, 0.0)
    m = sim.with_boxes(s.box_pos, s.box_size)
    d = sim.init_data(jnp.zeros(3), jnp.float32(0.0), jnp.zeros(6))
    from mujoco import mjx
    d = mjx.kinematics(m, d.replace(qpos=d.qpos.at[:7].set(root)))
    return s, cast(LAYOUT, m, d, sim.layout.camera_site)

  geomgroup = np.array([1, 0, 0, 0, 0, 0], np.uint8)
  hits = 0
  for trial in range(6):
    root = _random_pose(rng)
    s, depth = mjx_depth(jax.random.PRNGKey(trial), jnp.asarray(root, jnp.float32))
    mj = sim.c_model_with_boxes(s.box_pos, s.box_size)
    data = mujoco.MjData(mj)
    data.qpos[:] = 0
    data.qpos[:7] = root
    mujoco.mj_forward(mj, data)
    cam = sim.layout.camera_site
    pnt, vecs = LAYOUT.world_rays(data.site_xpos[cam], data.site_xmat[cam].reshape(3, 3))
    gid = np.zeros(1, np.int32)
    oracle = np.array([mujoco.mj_ray(mj, data, np.asarray(pnt, np.float64), np.asarray(v, np.float64),
                                     geomgroup, 1, -1, gid) for v in np.asarray(vecs)])
    np.testing.assert_allclose(np.asarray(depth), oracle, atol=2e-3)
    hits += (oracle >= 0).sum()
    # features: band means of valid hits, as a hand-written numpy reference
    feats = np.asarray(LAYOUT.features(jnp.asarray(oracle)))
    for k in (0, 30, 59, 60, 71):
      sel = LAYOUT.band == k
      z = oracle[sel]
      valid = (z >= 0) & (z <= 8.0)
      vals = np.where((z >= 0.2) & (z <= 1.5), z, 0.0)[valid]
      expected = np.clip(vals.mean() if valid.any() else 0.0, 0, 3)
      assert feats[k] == pytest.approx(expected, abs=1e-5)
  assert hits > 100  # the poses see the stairs and the floor


def test_beam_layout_shape_and_noise():
  assert LAYOUT.n_features == 72 and LAYOUT.n_rays == 72 * 4
  np.testing.assert_allclose(LAYOUT.dirs[:, 2], -1.0)
  depth = jnp.full(LAYOUT.n_rays, 1.0)
  clean = LAYOUT.features(depth)
  np.testing.assert_allclose(np.asarray(clean), 1.0)
  far = LAYOUT.features(jnp.full(LAYOUT.n_rays, 2.5))  # valid hit outside [0.2, 1.5] -> 0
  np.testing.assert_allclose(np.asarray(far), 0.0)


def test_beam_noise_hides_each_ray_with_its_probability():
  """Each band casts 4 rays at depths 0.4, 0.6, 0.8, 1.0 m; a ray is hidden with probability p.
  A band reads 0 only when all 4 are hidden (p^4), and otherwise the mean of its visible rays,
  whose expectation is 0.7 m by symmetry."""
  p = 0.5
  layout = BeamLayout(**{**vars(LAYOUT), "noise": p})
  depth = jnp.asarray(0.4 + 0.2 * _rank_within_band(layout.band), jnp.float32)
  keys = jax.random.split(jax.random.PRNGKey(0), 400)
  f = np.asarray(jax.vmap(lambda k: layout.features(depth, k))(keys)).ravel()
  n = f.size
  assert abs((f == 0).mean() - p**4) < 5 * np.sqrt(p**4 * (1 - p**4) / n)
  visible = f[f > 0]
  assert abs(visible.mean() - 0.7) < 0.01
  clean = np.asarray(LAYOUT.features(depth))
  np.testing.assert_allclose(clean, 0.7, atol=1e-6)  # no noise: every band's plain mean


def _rank_within_band(band: np.ndarray) -> np.ndarray:
  """0, 1, 2, 3 for the rays of each band, in ray order."""
  rank = np.zeros(len(band), np.int64)
  for k in np.unique(band):
    idx = np.nonzero(band == k)[0]
    rank[idx] = np.arange(len(idx))
  return rank

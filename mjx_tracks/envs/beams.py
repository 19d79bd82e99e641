"""Depth-beam features by ray casting from the robot's depth camera.

The original rendered a 640 x 480 depth image and averaged pixels: a vertical beam k is the mean of
the valid pixels of row band k (of N_v) inside a band_px-wide central column band; a horizontal
beam k is the mean over column band k (of N_h) inside a band_px-high central row band. Here each
band casts a small grid of rays (rays_per_band) through the centres of pixels of that band, with
a pinhole model of the camera (horizontal fov, resolution). A ray's distance is measured along the
camera axis (the depth image's z-depth). Rays that hit nothing within the camera's far range (or
are hidden by noise) are invalid; hits outside depth_range count as 0, as in the original.
Features are bounded to [0, 3].
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
from mujoco import mjx

from scenes.world import WORLD_GROUP

FEATURE_MAX = 3.0  # m
RAY_GROUPS = tuple(int(g == WORLD_GROUP) for g in range(6))  # rays see the world only, never the robot


@dataclasses.dataclass(frozen=True)
class BeamLayout:
  """Static ray directions in the camera frame and which band each ray belongs to."""

  dirs: np.ndarray  # (n_rays, 3), camera frame (x right, y up, looking along -z), z = -1
  band: np.ndarray  # (n_rays,) feature index: vertical beams first, then horizontal
  n_vertical: int
  n_horizontal: int
  depth_range: tuple[float, float]  # m
  far: float  # m, camera far range
  noise: float  # probability that a ray is hidden

  @staticmethod
  def create(hfov: float, resolution: tuple[int, int], n_vertical: int, n_horizontal: int,
             band_px: int, rays_per_band: tuple[int, int], depth_range: tuple[float, float],
             far: float, noise: float = 0.0) -> "BeamLayout":
    w, h = resolution
    f = (w / 2) / np.tan(hfov / 2)  # px
    ra, rc = rays_per_band

    def centres(lo, hi, k):  # k pixel centres spread over [lo, hi)
      return lo + (np.arange(k) + 0.5) * (hi - lo) / k

    us, vs, bands = [], [], []
    for k in range(n_vertical):  # row bands x central column band
      rows = centres(k * h / n_vertical, (k + 1) * h / n_vertical, ra)
      cols = centres(w / 2 - band_px / 2, w / 2 + band_px / 2, rc)
      uu, vv = np.meshgrid(cols, rows)
      us.append(uu.ravel()); vs.append(vv.ravel()); bands.append(np.full(uu.size, k))
    for k in range(n_horizontal):  # column bands x central row band
      cols = centres(k * w / n_horizontal, (k + 1) * w / n_horizontal, ra)
      rows = centres(h / 2 - band_px / 2, h / 2 + band_px / 2, rc)
      uu, vv = np.meshgrid(cols, rows)
      us.append(uu.ravel()); vs.append(vv.ravel()); bands.append(np.full(uu.size, n_vertical + k))
    u, v = np.concatenate(us or [np.zeros(0)]), np.concatenate(vs or [np.zeros(0)])
    dirs = np.stack([(u - w / 2) / f, -(v - h / 2) / f, -np.ones_like(u)], axis=-1).astype(np.float32)
    return BeamLayout(dirs, np.concatenate(bands or [np.zeros(0)]).astype(np.int32), n_vertical, n_horizontal,
                      tuple(depth_range), far, noise)

  @property
  def n_features(self) -> int:
    return self.n_vertical + self.n_horizontal

  @property
  def n_rays(self) -> int:
    return len(self.band)

  def world_rays(self, cam_pos: jax.Array, cam_mat: jax.Array) -> tuple[jax.Array, jax.Array]:
    """Ray origin (3,) and world directions (n_rays, 3), not normalized (camera-axis length 1)."""
    return cam_pos, jnp.asarray(self.dirs) @ cam_mat.T

  def features(self, depth: jax.Array, key: jax.Array | None = None, hidden=None) -> jax.Array:
    """Per-ray z-depth (-1 for no hit) -> (n_features,) band means, bounded to [0, 3]; each ray
    hidden with probability `hidden` (None: the layout's noise)."""
    valid = (depth >= 0) & (depth <= self.far)
    if key is not None and (hidden is not None or self.noise > 0):
      valid &= jax.random.uniform(key, depth.shape) >= (self.noise if hidden is None else hidden)
    lo, hi = self.depth_range
    value = jnp.where((depth >= lo) & (depth <= hi), depth, 0.0)
    band = jnp.asarray(self.band)
    total = jax.ops.segment_sum(jnp.where(valid, value, 0.0), band, self.n_features)
    count = jax.ops.segment_sum(valid.astype(jnp.float32), band, self.n_features)
    return jnp.clip(total / jnp.maximum(count, 1.0), 0.0, FEATURE_MAX)


def tilted(cam_mat: jax.Array, pitch) -> jax.Array:
  """The camera's orientation pitched by `pitch` rad about its x axis (> 0: looking further down)."""
  c, s = jnp.cos(pitch), jnp.sin(pitch)
  rot = jnp.array([[1.0, 0.0, 0.0], [0.0, c, s], [0.0, -s, c]])  # R_x(-pitch): -z turns toward -y
  return cam_mat @ rot


def cast(layout: BeamLayout, m: mjx.Model, d: mjx.Data, cam_site: int, pitch=None) -> jax.Array:
  """z-depth of every ray from the camera site (m; -1 where nothing is hit), the camera pitched by
  `pitch` rad (None: as mounted)."""
  cam_mat = d.site_xmat[cam_site] if pitch is None else tilted(d.site_xmat[cam_site], pitch)
  pnt, vecs = layout.world_rays(d.site_xpos[cam_site], cam_mat)
  dist, _ = jax.vmap(lambda v: mjx.ray(m, d, pnt, v, geomgroup=RAY_GROUPS))(vecs)
  return dist


def depth_beams(layout: BeamLayout, m: mjx.Model, d: mjx.Data, cam_site: int,
                key: jax.Array | None = None, pitch=None, range_noise=None, hidden=None) -> jax.Array:
  """Beam features (vertical then horizontal), in m, from one camera pose (pitched by `pitch` rad);
  with range_noise r, each hit's depth reads depth x (1 + N(0, r)) (a stereo camera's error grows
  with range); hidden: each ray's probability to be hidden (None: the layout's noise)."""
  depth = cast(layout, m, d, cam_site, pitch)
  k_hide = key
  if range_noise is not None and key is not None:
    k_hide, k_range = jax.random.split(key)
    depth = with_range_noise(depth, range_noise, k_range)
  return layout.features(depth, k_hide, hidden)


def with_range_noise(depth: jax.Array, r, key: jax.Array) -> jax.Array:
  """Each hit's depth x (1 + N(0, r)), at least 0; misses (-1) stay misses."""
  noisy = depth * (1.0 + r * jax.random.normal(key, depth.shape))
  return jnp.where(depth >= 0, jnp.maximum(noisy, 0.0), depth)

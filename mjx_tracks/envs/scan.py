"""Laser scan: distances to the world around the chassis, in the scanner's plane and, optionally,
in rings pitched down towards the floor (a multi-ring 3D lidar).

The paper's robots see through one forward depth camera, pitched down for stairs (robot 1: 0.46
rad, 1.2 rad wide): beside and behind the robot it sees nothing, and the camera's central row meets
the floor about 0.8 m ahead. Indoor tracked robots commonly carry a 2D lidar; this is one. Ray k of
N leaves the scanner (RobotSpec.lidar_pos, chassis frame) at yaw 2 pi k / N from the chassis' forward
axis (counter-clockwise, seen from above), in the chassis' x-y plane, and reads the distance (m) to
the first world surface (never the robot: beams.RAY_GROUPS), or `max_range` where nothing is hit
within it. With several `pitches` (rad, downward from the chassis' x-y plane;
observation.scan_pitches) the N rays are cast once per pitch, ring by ring (ray j N + k: ring j,
yaw 2 pi k / N). A ring pitched down by p from a scanner h above flat floor meets it h / tan(p)
away: the horizontal ring (p = 0) passes over anything lower than h (robot 1: 0.29 m, over
nav-obstacles' 0.05-0.15 m floor boxes), a pitched ring reads a box as a shorter range. With the
robustness suite's depth perturbations, a hit reads distance x (1 + N(0, r)) and each ray is lost
(reads max_range) with the hidden-ray probability.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
from mujoco import mjx

from mjx_tracks.envs.beams import RAY_GROUPS, with_range_noise


@dataclasses.dataclass(frozen=True)
class ScanLayout:
  """Static scan geometry: ray directions in the chassis frame and the range."""

  n_rays: int  # N_s, rays per ring (0: no scan)
  max_range: float  # m, what a ray reads where it hits nothing nearer
  mount: tuple[float, float, float]  # m, the scanner in the chassis frame
  pitches: tuple[float, ...] = (0.0,)  # rad, each ring's pitch down from the chassis' x-y plane

  @property
  def size(self) -> int:
    """Readings per scan: N_s x rings."""
    return self.n_rays * len(self.pitches)

  def directions(self) -> np.ndarray:
    """(rings x N_s, 3) unit vectors in the chassis frame, ray j N_s + k at yaw 2 pi k / N_s, pitched
    down by pitches[j]."""
    a = np.tile(2 * np.pi * np.arange(self.n_rays) / max(self.n_rays, 1), len(self.pitches))
    p = np.repeat(np.asarray(self.pitches, np.float64), self.n_rays)
    return np.stack([np.cos(a) * np.cos(p), np.sin(a) * np.cos(p), -np.sin(p)], axis=-1).astype(np.float32)

  def world_rays(self, body_pos: jax.Array, body_mat: jax.Array) -> tuple[jax.Array, jax.Array]:
    """Ray origin (3,) and unit world directions (rings x N_s, 3) for the chassis pose."""
    return body_pos + body_mat @ jnp.asarray(self.mount, jnp.float32), jnp.asarray(self.directions()) @ body_mat.T


def scan_ranges(layout: ScanLayout, m: mjx.Model, d: mjx.Data, body: int, key: jax.Array | None = None,
         range_noise=None, hidden=None) -> jax.Array:
  """(rings x N_s,) distances (m) in [0, max_range] from the scanner on `body` (module docstring)."""
  pnt, vecs = layout.world_rays(d.xpos[body], d.xmat[body])
  dist, _ = jax.vmap(lambda v: mjx.ray(m, d, pnt, v, geomgroup=RAY_GROUPS))(vecs)
  if key is not None and range_noise is not None:
    k_noise, k_hide = jax.random.split(key)
    dist = with_range_noise(dist, range_noise, k_noise)
    if hidden is not None:
      dist = jnp.where(jax.random.uniform(k_hide, dist.shape) < hidden, -1.0, dist)
  return jnp.where((dist >= 0) & (dist <= layout.max_range), dist, layout.max_range)

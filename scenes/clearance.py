"""Clearance: the 2D distance (m) from the robot's footprint to the walls and wall obstacles of an
area, pure JAX (the nav tasks' `reward.clearance_penalty` reads it).

The footprint is a rectangle of half-sizes (hx, hy) centred on the chassis origin and turned by its
yaw: every colliding robot geom, level at rest, lies inside it (mjx_tracks.sim.collisions.footprint_half).
Obstacles are axis-aligned boxes [lo, hi]; the area is the rectangle [area_lo, area_hi] inside its wall planes.
Two disjoint convex polygons are as far apart as the nearest pair of a vertex of one and the other
polygon, so the distance to a box is the least of the footprint's corners to the box and the box's
corners to the footprint; it is 0 where a corner of either lies inside the other. (Two rectangles
crossing like a plus sign, with no corner inside the other, read the distance of their corners:
physically a robot would have to pass through a wall to get there.) The distance to the walls is
the least distance of a footprint corner to the area's sides, 0 outside.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

_SIGNS = np.array([[-1.0, -1.0], [-1.0, 1.0], [1.0, -1.0], [1.0, 1.0]])  # corner signs (numpy: nothing touches a device at import)


def rectangle_corners(centre: jax.Array, yaw: jax.Array, half: jax.Array) -> jax.Array:
  """(4, 2) m: the corners of the rectangle centred at centre (2,), half-sizes half (2,), turned by yaw (rad)."""
  c, s = jnp.cos(yaw), jnp.sin(yaw)
  local = _SIGNS * half
  return centre + jnp.stack([c * local[:, 0] - s * local[:, 1], s * local[:, 0] + c * local[:, 1]], axis=-1)


def point_box_distance(p: jax.Array, lo: jax.Array, hi: jax.Array) -> jax.Array:
  """(n, k) m: from points p (n, 2) to boxes [lo, hi] (k, 2); 0 inside."""
  gap = jnp.maximum(jnp.maximum(lo - p[:, None], p[:, None] - hi), 0.0)
  return jnp.linalg.norm(gap, axis=-1)


def point_rectangle_distance(p: jax.Array, centre: jax.Array, yaw: jax.Array, half: jax.Array) -> jax.Array:
  """(n,) m: from points p (n, 2) to the turned rectangle (rectangle_corners); 0 inside."""
  d = p - centre
  c, s = jnp.cos(yaw), jnp.sin(yaw)
  local = jnp.stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]], axis=-1)
  return jnp.linalg.norm(jnp.maximum(jnp.abs(local) - half, 0.0), axis=-1)


def footprint_clearance(centre: jax.Array, yaw: jax.Array, half: jax.Array, box_lo: jax.Array, box_hi: jax.Array,
                        area_lo: jax.Array, area_hi: jax.Array) -> jax.Array:
  """() m: the footprint's distance to the nearest box [box_lo, box_hi] (k, 2) or wall of the area
  (module docstring)."""
  corners = rectangle_corners(centre, yaw, half)
  to_boxes = jnp.min(point_box_distance(corners, box_lo, box_hi), axis=0)  # (k,)
  box_corners = jnp.stack([jnp.stack([box_lo[:, 0], box_lo[:, 1]], -1), jnp.stack([box_lo[:, 0], box_hi[:, 1]], -1),
                           jnp.stack([box_hi[:, 0], box_lo[:, 1]], -1), jnp.stack([box_hi[:, 0], box_hi[:, 1]], -1)],
                          axis=1)  # (k, 4, 2)
  from_boxes = jnp.min(point_rectangle_distance(box_corners.reshape(-1, 2), centre, yaw, half).reshape(-1, 4), axis=1)
  to_walls = jnp.maximum(jnp.min(jnp.concatenate([corners - area_lo, area_hi - corners])), 0.0)
  return jnp.minimum(jnp.min(jnp.minimum(to_boxes, from_boxes), initial=jnp.inf), to_walls)

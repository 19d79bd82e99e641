"""Spiral (helical) staircases, terrain kinds laid out from xi = (radius, angle, riser, steps).

The stairs' centre line is a circle of `radius` (m) about (0, radius): it starts at the origin
heading +x and turns left (counter-clockwise seen from above). Its point at angle phi (rad) is
(radius sin phi, radius (1 - cos phi)) and its heading there is phi. Step k < steps - 1 spans
phi in [k angle, (k + 1) angle]: a box yawed by its mid angle, WIDTH across the centre line
(from radius - 1 to radius + 1 m) and long enough along it to cover the sector up to the outer
edge, z in [0, (k + 1) riser]. The top step is a straight landing LANDING_LENGTH long from the
centre line's point at (steps - 1) angle, along its heading. Spirals stand in the open: no side
walls; driving off a side is a fall. Spawns and goals are points on the centre line's extension,
1 m before the first step and 1 m onto the landing.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from scenes.scene import Ends
from scenes.staircase import (GOAL_ABOVE_TREAD, GOAL_PAST_EDGE, LANDING_LENGTH, SPAWN_BEFORE_STAIRS, WIDTH,
                              park_unused)


def centre_line(radius, phi) -> jax.Array:
  """(x, y) of the stairs' centre line at angle phi (rad); its heading there is phi."""
  return jnp.stack([radius * jnp.sin(phi), radius * (1.0 - jnp.cos(phi))], axis=-1)


def _heading(phi) -> jax.Array:
  """The unit vector (x, y) of heading phi (rad)."""
  return jnp.stack([jnp.cos(phi), jnp.sin(phi)], axis=-1)


def landing_angle(xi) -> jax.Array:
  """The centre line's angle where the landing starts, (steps - 1) angle (rad)."""
  return (xi[3].astype(jnp.int32) - 1) * xi[1]


def spiral_boxes(xi, pool: int) -> tuple[jax.Array, jax.Array, jax.Array]:
  """Centres, half-sizes (pool, 3) and yaws (pool,) of a spiral's steps and landing (m, rad)."""
  radius, angle, riser, steps = xi[0], xi[1], xi[2], xi[3].astype(jnp.int32)
  k = jnp.arange(pool)
  end = landing_angle(xi)
  is_landing = k == steps - 1
  mid = (k + 0.5) * angle
  xy = jnp.where(is_landing[:, None], centre_line(radius, end) + LANDING_LENGTH / 2 * _heading(end),
                 centre_line(radius, mid))
  along = jnp.where(is_landing, LANDING_LENGTH / 2, (radius + WIDTH / 2) * jnp.tan(angle / 2))  # half-length, m
  top = (k + 1) * riser
  pos = jnp.concatenate([xy, top[:, None] / 2], axis=-1)
  size = jnp.stack([along, jnp.full_like(along, WIDTH / 2), top / 2], axis=-1)
  used = k < steps
  pos, size = park_unused(pos, size, used)
  return pos, size, jnp.where(used, jnp.where(is_landing, end, mid), 0.0)


def _landing_point(xi) -> tuple[jax.Array, jax.Array]:
  """The point 1 m onto the landing along the centre line (x, y, ground z; m) and its heading (rad)."""
  radius, riser, steps = xi[0], xi[2], xi[3].astype(jnp.int32)
  end = landing_angle(xi)
  xy = centre_line(radius, end) + GOAL_PAST_EDGE * _heading(end)
  return jnp.concatenate([xy, (steps * riser)[None]]), end


def spiral_up(xi, key, pool: int):
  """A spiral staircase, climbed: spawn 1 m before the first step facing it, goal 1 m onto the landing."""
  top, _ = _landing_point(xi)
  spawn = jnp.array([-SPAWN_BEFORE_STAIRS, 0.0, 0.0])
  return *spiral_boxes(xi, pool), Ends(spawn, jnp.float32(0.0), top + jnp.array([0.0, 0.0, GOAL_ABOVE_TREAD]),
                                       jnp.float32(0.0))


def spiral_down(xi, key, pool: int):
  """A spiral staircase, descended: spawn 1 m onto the landing facing down, goal 1 m before the first step."""
  top, heading = _landing_point(xi)
  goal = jnp.array([-GOAL_PAST_EDGE, 0.0, GOAL_ABOVE_TREAD])
  return *spiral_boxes(xi, pool), Ends(top, heading + jnp.pi, goal, jnp.float32(0.0))

"""Free-space (geodesic) distance in a 2D area with axis-aligned box obstacles, pure JAX.

The robot is a disc of radius `clearance`: every obstacle is inflated by it (a Minkowski sum with
a square, so slightly conservative at corners) and the area's walls move in by it. The shortest
path from p to the goal in such a domain runs straight between the inflated boxes' corners
(a visibility graph): its length is

  G(p) = |p - goal|                                   if the segment p-goal misses every box,
       = min over corners c seen from p of |p - c| + D(c)   otherwise,

with D(c) the shortest corner-to-goal distance through the graph (Bellman-Ford from the goal over
the corners, as many rounds as there are corners). Corners outside the area or inside another box
are not nodes. An inflated box that contains p (the robot close to an obstacle) or the goal (a goal
within the clearance of an obstacle) is tested without inflation for that point's own segments, so
G stays finite there. Where no path exists, G = inf.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

NODE_OFFSET = 1e-3  # m, corners sit this far outside their inflated box
GRAZE = 1e-4  # m, a segment must enter a box this deep to count as blocked (corner grazing passes)


def segment_blocked(a: jax.Array, b: jax.Array, lo: jax.Array, hi: jax.Array) -> jax.Array:
  """Whether the segment a-b (2,) crosses the interior of any box [lo, hi] ((k, 2) each), by the
  slab test."""
  d = b - a
  safe = jnp.where(jnp.abs(d) < 1e-9, 1e-9, d)
  t0, t1 = (lo - a) / safe, (hi - a) / safe  # (k, 2) entry / exit parameters per axis
  flat = jnp.abs(d) < 1e-9  # parallel to a slab: inside it for every t, or never
  inside = (a > lo) & (a < hi)
  t_in = jnp.where(flat, jnp.where(inside, -jnp.inf, jnp.inf), jnp.minimum(t0, t1))
  t_out = jnp.where(flat, jnp.where(inside, jnp.inf, -jnp.inf), jnp.maximum(t0, t1))
  enter, leave = jnp.max(t_in, axis=-1), jnp.min(t_out, axis=-1)
  enter, leave = jnp.maximum(enter, 0.0), jnp.minimum(leave, 1.0)
  return jnp.any((leave - enter) * jnp.linalg.norm(d) > GRAZE)


def _corners(lo: jax.Array, hi: jax.Array) -> jax.Array:
  """(4k, 2) corners of k boxes, NODE_OFFSET outside each."""
  lo, hi = lo - NODE_OFFSET, hi + NODE_OFFSET
  return jnp.concatenate([jnp.stack([lo[:, 0], lo[:, 1]], -1), jnp.stack([lo[:, 0], hi[:, 1]], -1),
                          jnp.stack([hi[:, 0], lo[:, 1]], -1), jnp.stack([hi[:, 0], hi[:, 1]], -1)])


def _own_boxes(q: jax.Array, box_lo, box_hi, lo, hi) -> tuple[jax.Array, jax.Array]:
  """The boxes q's own segments are tested against: an inflated box [lo, hi] that contains q as it
  is [box_lo, box_hi], not inflated (so a point near an obstacle keeps a finite distance)."""
  holds = jnp.all((q > lo) & (q < hi), axis=-1)[:, None]
  return jnp.where(holds, box_lo, lo), jnp.where(holds, box_hi, hi)


def geodesic_distance(p: jax.Array, goal: jax.Array, box_lo: jax.Array, box_hi: jax.Array,
                      area_lo: jax.Array, area_hi: jax.Array, clearance: float) -> jax.Array:
  """G(p) (m, module docstring): p, goal (2,); obstacles [box_lo, box_hi] (k, 2) m; the area
  [area_lo, area_hi] (2,) m, walls included; clearance (m)."""
  lo, hi = box_lo - clearance, box_hi + clearance
  nodes = _corners(lo, hi)
  inside_area = jnp.all((nodes >= area_lo + clearance) & (nodes <= area_hi - clearance), axis=-1)
  in_box = jnp.any(jnp.all((nodes[:, None] > lo) & (nodes[:, None] < hi), axis=-1), axis=-1)
  valid = inside_area & ~in_box
  blocked = jax.vmap(lambda a: jax.vmap(lambda b: segment_blocked(a, b, lo, hi))(nodes))(nodes)
  edge = jnp.where(valid[:, None] & valid[None, :] & ~blocked,
                   jnp.linalg.norm(nodes[:, None] - nodes[None, :], axis=-1), jnp.inf)
  g_lo, g_hi = _own_boxes(goal, box_lo, box_hi, lo, hi)
  to_goal = jax.vmap(lambda a: segment_blocked(a, goal, g_lo, g_hi))(nodes)
  d = jnp.where(valid & ~to_goal, jnp.linalg.norm(nodes - goal, axis=-1), jnp.inf)
  d = jax.lax.fori_loop(0, nodes.shape[0], lambda _, d: jnp.minimum(d, jnp.min(edge + d[None, :], axis=1)), d)
  p_lo, p_hi = _own_boxes(p, box_lo, box_hi, lo, hi)
  direct = jnp.where(segment_blocked(p, goal, p_lo, p_hi), jnp.inf, jnp.linalg.norm(p - goal))
  seen = jax.vmap(lambda c: ~segment_blocked(p, c, p_lo, p_hi))(nodes)
  via = jnp.min(jnp.where(seen & valid, jnp.linalg.norm(nodes - p, axis=-1) + d, jnp.inf))
  return jnp.minimum(direct, via)

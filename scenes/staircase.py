"""A straight staircase as a fixed pool of step boxes whose poses and sizes come from xi = (l, h, n).

One compiled model holds N_MAX step boxes. Each environment places and sizes them from its own
xi, so one batched step call simulates as many different staircases as there are environments.
Step k (0-based, k < n - 1) is a block x in [k l, (k+1) l], z in [0, (k+1) h]; the top step is the
landing, x in [(n-1) l, (n-1) l + LANDING_LENGTH], z in [0, n h]; unused boxes are parked far
below the floor. The first riser is at x = 0; the stairs rise toward +x.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from flax import struct

from mjx_tracks.robots.mjcf import WORLD_CONAFFINITY, WORLD_CONTYPE

N_MAX = 7  # steps in the pool (the reference's n_max)
WIDTH = 2.0  # m, between the side walls
LANDING_LENGTH = 3.0  # m, top landing
WALL_HEIGHT = 2.0  # m above the landing (walls are planes: infinitely tall in the physics)
GOAL_PAST_EDGE = 1.0  # m, ascent goal past the top step edge; descent goal before the first step
GOAL_ABOVE_TREAD = 0.085  # m
SPAWN_BEFORE_STAIRS = 1.0  # m, ascent spawn in front of the first riser
PARK = (-50.0, 0.0, -10.0)  # m, where unused boxes go
STEP_NAME = "step{}"


@struct.dataclass
class Staircase:
  """Geometry of one staircase; fields may carry a batch axis."""

  tread: jax.Array  # l, m
  riser: jax.Array  # h, m
  steps: jax.Array  # n, integer count >= 1

  def top_edge_x(self) -> jax.Array:
    """x of the landing's front edge (m)."""
    return (self.steps - 1) * self.tread

  def top_z(self) -> jax.Array:
    return self.steps * self.riser


def world_xml(n_max: int = N_MAX) -> str:
  """Floor, side walls (planes at y = +-WIDTH/2) and the pool of step boxes."""
  world = f'contype="{WORLD_CONTYPE}" conaffinity="{WORLD_CONAFFINITY}" condim="3" material="world"'
  half = WIDTH / 2
  steps = "\n".join(
      f'<geom name="{STEP_NAME.format(k)}" type="box" pos="{PARK[0] - k} {PARK[1]} {PARK[2]}" '
      f'size="0.1 0.1 0.1" {world} rgba=".7 .7 .65 1"/>' for k in range(n_max))
  # planes' normals point into the corridor (a plane's normal is its local +z)
  return f"""
    <geom name="floor" type="plane" size="0 0 1" {world} rgba=".5 .55 .5 1"/>
    <geom name="wall_left" type="plane" pos="0 {half} 0" zaxis="0 -1 0" size="0 0 1" {world} rgba=".6 .6 .7 .3"/>
    <geom name="wall_right" type="plane" pos="0 {-half} 0" zaxis="0 1 0" size="0 0 1" {world} rgba=".6 .6 .7 .3"/>
    {steps}"""


def step_boxes(stairs: Staircase, n_max: int = N_MAX) -> tuple[jax.Array, jax.Array]:
  """Centres (n_max, 3) and half-sizes (n_max, 3) of the step boxes of one staircase (m)."""
  k = jnp.arange(n_max)
  l, h, n = stairs.tread, stairs.riser, stairs.steps
  is_landing = k == n - 1
  used = k < n
  x0 = k * l
  length = jnp.where(is_landing, LANDING_LENGTH, l)
  top = (k + 1) * h
  pos = jnp.stack([x0 + length / 2, jnp.zeros_like(x0), top / 2], axis=-1)
  size = jnp.stack([length / 2, jnp.full_like(x0, WIDTH / 2), top / 2], axis=-1)
  parked_pos = jnp.array(PARK) + jnp.stack([-3.0 * k, 0 * k, 0 * k], axis=-1)
  pos = jnp.where(used[:, None], pos, parked_pos)
  size = jnp.where(used[:, None], size, 0.1)
  return pos, size


def ascent_goal(stairs: Staircase) -> jax.Array:
  """Goal 1 m past the top step edge, 0.085 m above the landing (m)."""
  return jnp.stack([stairs.top_edge_x() + GOAL_PAST_EDGE, jnp.zeros_like(stairs.tread),
                    stairs.top_z() + GOAL_ABOVE_TREAD], axis=-1)


def descent_goal(stairs: Staircase) -> jax.Array:
  """Goal 1 m before the first riser, on the floor (m)."""
  return jnp.stack([jnp.full_like(stairs.tread, -GOAL_PAST_EDGE), jnp.zeros_like(stairs.tread),
                    jnp.full_like(stairs.tread, GOAL_ABOVE_TREAD)], axis=-1)


def ascent_spawn(stairs: Staircase) -> tuple[jax.Array, jax.Array]:
  """(x, y, ground z) and yaw of the ascent spawn: in front of the first step, facing it."""
  z = jnp.zeros_like(stairs.tread)
  return jnp.stack([z - SPAWN_BEFORE_STAIRS, z, z], axis=-1), z


def descent_spawn(stairs: Staircase) -> tuple[jax.Array, jax.Array]:
  """(x, y, ground z) and yaw of the descent spawn: on the landing, facing down the stairs."""
  z = jnp.zeros_like(stairs.tread)
  pos = jnp.stack([stairs.top_edge_x() + GOAL_PAST_EDGE, z, stairs.top_z()], axis=-1)
  return pos, z + jnp.pi

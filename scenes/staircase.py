"""A straight staircase as a fixed pool of step boxes whose poses and sizes come from xi = (l, h, n).

One compiled model holds a pool of step boxes, as many as the task's longest staircase (up to
MAX_STEPS). Each environment places and sizes them from its own xi, so one batched step call
simulates as many different staircases as there are environments.
Step k (0-based, k < n - 1) is a block x in [k l, (k+1) l], z in [0, (k+1) h]; the top step is the
landing, x in [(n-1) l, (n-1) l + LANDING_LENGTH], z in [0, n h]; unused boxes are parked far
below the floor. The first riser is at x = 0; the stairs rise toward +x.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp

from flax import struct

from scenes import samplers
from scenes.samplers import Ranges
from scenes.scene import SceneState
from scenes.terrain_kinds import MAX_STEPS, STAIRS
from scenes.world import PARKED_HALF, parked_box_xml, parked_xyz, world_geom_attrs

N_MAX = 7  # the reference's n_max: the paper's longest staircase (the default pool)
WIDTH = 2.0  # m, between the side walls
LANDING_LENGTH = 3.0  # m, top landing
GOAL_PAST_EDGE = 1.0  # m, ascent goal past the top step edge; descent goal before the first step
GOAL_ABOVE_TREAD = 0.085  # m
GOAL_HALFWIDTH = WIDTH / 2  # m: the goal is a line across the staircase (see StairScene.sample)
SPAWN_BEFORE_STAIRS = 1.0  # m, ascent spawn in front of the first riser


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


def world_xml(n_max: int = N_MAX, walls: bool = True) -> str:
  """Floor, side walls (planes at y = +-WIDTH/2; none if not walls) and the pool of step boxes."""
  world = world_geom_attrs()
  half = WIDTH / 2
  steps = "\n".join(parked_box_xml(k, ".7 .7 .65 1") for k in range(n_max))
  # planes' normals point into the corridor (a plane's normal is its local +z)
  side = f"""
    <geom name="wall_left" type="plane" pos="0 {half} 0" zaxis="0 -1 0" size="0 0 1" {world} rgba=".6 .6 .7 .3"/>
    <geom name="wall_right" type="plane" pos="0 {-half} 0" zaxis="0 1 0" size="0 0 1" {world} rgba=".6 .6 .7 .3"/>"""
  return f"""
    <geom name="floor" type="plane" size="0 0 1" {world} rgba=".5 .55 .5 1"/>{side if walls else ""}
    {steps}"""


def step_boxes(stairs: Staircase, n_max: int = N_MAX) -> tuple[jax.Array, jax.Array]:
  """Centres (n_max, 3) and half-sizes (n_max, 3) of the step boxes of one staircase (m)."""
  return boxes_from_treads(jnp.full((n_max,), stairs.tread), stairs.riser, stairs.steps)


def tread_starts(treads: jax.Array) -> jax.Array:
  """x (m) of each step's riser: the sum of the treads before it."""
  return jnp.concatenate([jnp.zeros(1, treads.dtype), jnp.cumsum(treads)[:-1]])


def boxes_from_treads(treads: jax.Array, riser: jax.Array, steps: jax.Array) -> tuple[jax.Array, jax.Array]:
  """Boxes (centres, half-sizes; (len(treads), 3), m) of a staircase whose step k < steps - 1 has
  tread treads[k] and top (k + 1) riser; step steps - 1 is the landing; the rest are parked."""
  k = jnp.arange(treads.shape[0])
  is_landing = k == steps - 1
  used = k < steps
  x0 = tread_starts(treads)
  length = jnp.where(is_landing, LANDING_LENGTH, treads)
  top = (k + 1) * riser
  pos = jnp.stack([x0 + length / 2, jnp.zeros_like(x0), top / 2], axis=-1)
  size = jnp.stack([length / 2, jnp.full_like(x0, WIDTH / 2), top / 2], axis=-1)
  return park_unused(pos, size, used)


def park_unused(pos: jax.Array, size: jax.Array, used: jax.Array) -> tuple[jax.Array, jax.Array]:
  """Boxes where used, else small boxes at their parking spots (scenes.world.parked_xyz)."""
  k = jnp.arange(pos.shape[0], dtype=pos.dtype)
  parked_pos = jnp.stack(jnp.broadcast_arrays(*parked_xyz(k)), axis=-1).astype(pos.dtype)
  return jnp.where(used[:, None], pos, parked_pos), jnp.where(used[:, None], size, PARKED_HALF)


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


STAIR_PARAMS = STAIRS.names  # xi = (l m, h m, n)
STAIR_HARD = STAIRS.hard  # hardest: short treads, tall risers, many steps
STAIR_LIMITS = STAIRS.limits  # what the generator supports (m, m, count)


def stair_ranges(tread: tuple[float, float], riser: tuple[float, float],
                 steps: tuple[int, int]) -> Ranges:
  """The sampler ranges of xi = (tread, riser, steps) with their hard ends."""
  return Ranges(names=STAIR_PARAMS, low=(tread[0], riser[0], float(steps[0])),
                high=(tread[1], riser[1], float(steps[1])), integer=(False, False, True),
                hard=STAIR_HARD)


def stair_ends(stairs: Staircase, up: bool | jax.Array):
  """((spawn, yaw), goal, ahead) of an ascent if up else a descent; up may be data (a traced bool:
  both computed, one picked), e.g. a draw's direction (runs of both directions in one program)."""
  ascent, descent = (ascent_spawn(stairs), ascent_goal(stairs), 1.0), (descent_spawn(stairs), descent_goal(stairs), -1.0)
  if isinstance(up, bool):
    return ascent if up else descent
  return jax.tree_util.tree_map(lambda a, d: jnp.where(up, a, d), ascent, descent)


SPAWN_Y = 0.75  # m, random spawn / goal lateral offset ~ U(-0.75, 0.75)
SPAWN_YAW = jnp.pi / 2  # rad, random spawn yaw offset ~ U(-pi/2, pi/2)


def randomized_ends(keys: list[jax.Array], spawn: jax.Array, yaw: jax.Array, goal: jax.Array, ahead: float,
                    random_spawn: bool, random_goal: bool) -> tuple[jax.Array, jax.Array, jax.Array]:
  """Spawn, yaw and goal with the random offsets asked for (keys: four); ahead: +1 if the goal lies
  toward +x."""
  k_y, k_yaw, k_gy, k_gx = keys
  if random_spawn:
    spawn = spawn.at[1].set(jax.random.uniform(k_y, minval=-SPAWN_Y, maxval=SPAWN_Y))  # y ~ U(-0.75, 0.75) m
    yaw = yaw + jax.random.uniform(k_yaw, minval=-SPAWN_YAW, maxval=SPAWN_YAW)  # yaw offset ~ U(-pi/2, pi/2)
  if random_goal:
    goal = goal.at[1].set(jax.random.uniform(k_gy, minval=-SPAWN_Y, maxval=SPAWN_Y))  # y ~ U(-0.75, 0.75) m
    goal = goal.at[0].add(ahead * jax.random.uniform(k_gx, minval=-0.5, maxval=0.5))  # x offset ~ U(-0.5, 0.5) m
  return spawn, yaw, goal


@dataclasses.dataclass(frozen=True)
class StairScene:
  """Ascent or descent of a randomized straight staircase."""

  direction: str  # "up" | "down"
  sampler: str  # scenes.samplers.SAMPLERS
  variant: str  # incremental variant (scenes.samplers.VARIANTS)
  ranges: Ranges  # of xi = (tread, riser, steps): stair_ranges(...)
  random_spawn: bool
  random_goal: bool

  def __post_init__(self):
    if self.direction not in ("up", "down"):
      raise ValueError(f"stairs direction must be 'up' or 'down', got {self.direction!r}")
    if self.ranges.names != STAIR_PARAMS:
      raise ValueError(f"stair ranges must be named {STAIR_PARAMS}")
    lo, hi = self.ranges.low, self.ranges.high
    if not (lo[0] > 0 and lo[1] > 0 and 1 <= lo[2] and hi[2] <= MAX_STEPS):
      raise ValueError(f"stair ranges need tread, riser > 0 and 1 <= steps <= {MAX_STEPS}")

  @property
  def n_boxes(self) -> int:
    """The box pool: the task's longest staircase."""
    return int(self.ranges.high[2])

  def world_xml(self) -> str:
    return world_xml(self.n_boxes)

  def stairs(self, xi: jax.Array) -> Staircase:
    return Staircase(tread=xi[0], riser=xi[1], steps=xi[2].astype(jnp.int32))

  def sample(self, key: jax.Array, eps: jax.Array, draw: samplers.Draw | None = None) -> SceneState:
    """Draws xi (from the draw, if given, instead of this scene's sampler and ranges), places the
    boxes, the spawn (ground point, yaw) and the goal."""
    k_xi, *k_ends = jax.random.split(key, 5)
    xi = samplers.sample(k_xi, eps, self.ranges, self.sampler, self.variant, draw)
    st = self.stairs(xi)
    pos, size = step_boxes(st, self.n_boxes)
    up = self.direction == "up" if draw is None or draw.ascent is None else draw.ascent
    (spawn, yaw), goal, ahead = stair_ends(st, up)
    spawn, yaw, goal = randomized_ends(k_ends, spawn, yaw, goal, ahead, self.random_spawn, self.random_goal)
    # the goal is a line across the staircase (the stair modes cannot steer nor observe lateral
    # drift); a random goal is a point with a random lateral offset, for modes that steer
    halfwidth = jnp.float32(0.0 if self.random_goal else GOAL_HALFWIDTH)
    return SceneState(pos, size, jnp.zeros(pos.shape[0]), spawn, yaw, goal, halfwidth, xi, jnp.int32(0))

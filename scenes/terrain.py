"""Terrains beyond the straight staircase: each a row of boxes in the stairs' corridor, placed from
its parameters xi; a task draws one of its kinds per episode.

Heights are from the floor (m); x runs along the corridor (2 m wide, walls at y = +-1); the robot
drives toward +x, 1 m in front of the terrain, and its goal is a line across the corridor 1 m past
the terrain, 0.085 m above the ground there, unless said otherwise:
  step_up(height):          one box x in [0, 3], z in [0, height]; the goal is on top.
  step_down(height):        the same box; the robot starts on it, 1 m from its edge, facing -x, and
                            its goal is on the floor 1 m in front of the box.
  uplift(height, length):   one box x in [0, length], z in [0, height].
  rails(height, gap):       RAILS bars across the corridor, RAIL_THICKNESS along x, their fronts
                            `gap` apart, z in [0, height].
  waves(amplitude, wavelength): WAVES wavelengths of the bump z = amplitude (1 - cos(2 pi x /
                            wavelength)) / 2, as WAVE_SEGMENTS boxes per wavelength, each as high as
                            the bump at its centre.
  blocks(height, length):   a BLOCK_ROWS x BLOCK_COLS grid of stepping blocks, `length` along x and
                            WIDTH / BLOCK_COLS across, block heights ~ U(0.2, 1) height (drawn per
                            block and episode; in the scene's box sizes).
  landing_up(tread, riser, steps, landing): a staircase (scenes.staircase) whose step steps // 2
                            (1-based) has a mid landing `landing` long; ascent.
  landing_down(...):        the same staircase, descended (spawn on the top landing, goal in front).
  spiral_up(radius, angle, riser, steps), spiral_down(...): spiral staircases (scenes.spiral),
                            yawed boxes in the open (no side walls), with point goals.
Every corridor kind's world is the same: the corridor and POOL boxes (a kind parks those it does not
use), so the tasks of different kinds compile to the same program; the spirals' world is the same
without the walls, so a task draws corridor kinds or spirals, not both.
"""

from __future__ import annotations

import dataclasses
from typing import Callable

import jax
import jax.numpy as jnp
import numpy as np

from scenes import samplers, spiral
from scenes.samplers import Ranges
from scenes.scene import Ends, SceneState
from scenes.staircase import (GOAL_ABOVE_TREAD, GOAL_HALFWIDTH, GOAL_PAST_EDGE, LANDING_LENGTH,
                              SPAWN_BEFORE_STAIRS, WIDTH, boxes_from_treads, park_unused, randomized_ends,
                              tread_starts, world_xml)
from scenes.terrain_kinds import TERRAIN_PARAMS, corridor_world

POOL = 16  # boxes of every terrain world: the most any kind uses
RAILS, RAIL_THICKNESS = 4, 0.1  # bars, m
WAVES, WAVE_SEGMENTS = 2, 8  # wavelengths, boxes per wavelength
BLOCK_ROWS, BLOCK_COLS = 4, 4
BLOCK_MIN = 0.2  # lowest block, as a fraction of `height`
MIN_HALF = 1e-3  # m, the thinnest half-size a box keeps (a box of zero size is no box)


def _forward(end_x, end_z) -> Ends:
  """Spawn 1 m before x = 0 facing +x; goal 1 m past end_x at ground height end_z."""
  return Ends(jnp.array([-SPAWN_BEFORE_STAIRS, 0.0, 0.0]), jnp.float32(0.0),
              jnp.stack([end_x + GOAL_PAST_EDGE, 0.0 * end_x, end_z + GOAL_ABOVE_TREAD]), jnp.float32(GOAL_HALFWIDTH))


def _backward(edge_x, top_z) -> Ends:
  """Spawn on a top landing 1 m past its edge edge_x facing -x; goal on the floor 1 m before x = 0."""
  return Ends(jnp.stack([edge_x + GOAL_PAST_EDGE, 0.0 * edge_x, top_z]), jnp.float32(jnp.pi),
              jnp.array([-GOAL_PAST_EDGE, 0.0, GOAL_ABOVE_TREAD]), jnp.float32(GOAL_HALFWIDTH))


def _row(x0, length, top, y0=None, width=None) -> tuple[jax.Array, jax.Array]:
  """Boxes x in [x0, x0 + length], z in [0, top], y in [y0, y0 + width] (default: the corridor)."""
  y0 = jnp.full_like(x0, -WIDTH / 2) if y0 is None else y0
  width = jnp.full_like(x0, WIDTH) if width is None else width
  pos = jnp.stack([x0 + length / 2, y0 + width / 2, top / 2], axis=-1)
  size = jnp.maximum(jnp.stack([length / 2, width / 2, top / 2], axis=-1), MIN_HALF)
  return pos, size


def _pool(pos, size) -> tuple[jax.Array, jax.Array, jax.Array]:
  """k axis-aligned boxes padded to POOL with parked ones: centres, half-sizes, yaws."""
  k = pos.shape[0]
  pad = lambda a: jnp.concatenate([a, jnp.zeros((POOL - k, 3), a.dtype)])  # noqa: E731
  return *park_unused(pad(pos), pad(size), jnp.arange(POOL) < k), jnp.zeros(POOL)


def _stairs(treads, riser, steps):
  """A staircase's pool (centres, half-sizes, yaws), its top edge x and its top height (m)."""
  pos, size = boxes_from_treads(treads, riser, steps)
  return pos, size, jnp.zeros(POOL), tread_starts(treads)[steps - 1], steps * riser


def step_up(xi, key):
  """One step of height xi[0], climbed."""
  pos, size, yaw, edge, top = _stairs(jnp.full(POOL, LANDING_LENGTH), xi[0], jnp.int32(1))
  return pos, size, yaw, _forward(edge, top)


def step_down(xi, key):
  """One step of height xi[0], driven down."""
  pos, size, yaw, edge, top = _stairs(jnp.full(POOL, LANDING_LENGTH), xi[0], jnp.int32(1))
  return pos, size, yaw, _backward(edge, top)


def _landing_treads(xi):
  """Per-step treads of a mid-landing staircase (step steps // 2 is the landing) and its step count."""
  tread, steps, landing = xi[0], xi[2].astype(jnp.int32), xi[3]
  return jnp.where(jnp.arange(POOL) == steps // 2 - 1, landing, tread), steps


def landing_up(xi, key):
  """A mid-landing staircase, climbed."""
  treads, steps = _landing_treads(xi)
  pos, size, yaw, edge, top = _stairs(treads, xi[1], steps)
  return pos, size, yaw, _forward(edge, top)


def landing_down(xi, key):
  """A mid-landing staircase, descended."""
  treads, steps = _landing_treads(xi)
  pos, size, yaw, edge, top = _stairs(treads, xi[1], steps)
  return pos, size, yaw, _backward(edge, top)


def uplift(xi, key):
  """One box of height xi[0] and length xi[1] to cross."""
  height, length = xi[0], xi[1]
  pos, size = _row(jnp.zeros(1), length[None], height[None])
  return *_pool(pos, size), _forward(length, 0.0 * length)


def rails(xi, key):
  """RAILS bars of height xi[0], their fronts xi[1] apart."""
  height, gap = xi[0], xi[1]
  x0 = jnp.arange(RAILS) * gap
  pos, size = _row(x0, jnp.full(RAILS, RAIL_THICKNESS), jnp.full(RAILS, height))
  return *_pool(pos, size), _forward(x0[-1] + RAIL_THICKNESS, 0.0 * gap)


def waves(xi, key):
  """WAVES cosine bumps of crest xi[0] and wavelength xi[1], WAVE_SEGMENTS boxes each."""
  amplitude, wavelength = xi[0], xi[1]
  n = WAVES * WAVE_SEGMENTS
  seg = wavelength / WAVE_SEGMENTS
  centre = (jnp.arange(n) + 0.5) / WAVE_SEGMENTS  # in wavelengths
  top = amplitude * (1.0 - jnp.cos(2.0 * jnp.pi * centre)) / 2.0
  pos, size = _row(jnp.arange(n) * seg, jnp.full(n, seg), top)
  return *_pool(pos, size), _forward(n * seg, 0.0 * seg)


def blocks(xi, key):
  """A grid of stepping blocks up to xi[0] high, xi[1] long, heights drawn from key."""
  height, length = xi[0], xi[1]
  row, col = jnp.divmod(jnp.arange(BLOCK_ROWS * BLOCK_COLS), BLOCK_COLS)
  tops = height * jax.random.uniform(key, (BLOCK_ROWS * BLOCK_COLS,), minval=BLOCK_MIN, maxval=1.0)  # ~ U(0.2, 1) height
  across = WIDTH / BLOCK_COLS
  pos, size = _row(row * length, jnp.full(row.shape, length), tops, -WIDTH / 2 + col * across,
                   jnp.full(row.shape, across))
  return *_pool(pos, size), _forward(BLOCK_ROWS * length, 0.0 * length)


LAYOUTS: dict[str, Callable] = {  # kind -> layout(xi, key) -> (box centres, half-sizes (POOL, 3), yaws (POOL,), Ends)
    "step_up": step_up, "step_down": step_down, "uplift": uplift, "rails": rails, "waves": waves,
    "blocks": blocks, "landing_up": landing_up, "landing_down": landing_down,
    "spiral_up": lambda xi, key: spiral.spiral_up(xi, key, POOL),
    "spiral_down": lambda xi, key: spiral.spiral_down(xi, key, POOL)}
assert set(LAYOUTS) == set(TERRAIN_PARAMS)


def terrain_ranges(kinds: tuple[str, ...], ranges: dict[str, dict[str, tuple[float, float]]]) -> Ranges:
  """The sampler ranges of a task's xi: the parameters of each of its kinds in turn, named
  KIND.PARAM; ranges: {kind: {param: (min, max)}}."""
  names, low, high, integer, hard = [], [], [], [], []
  for kind in kinds:
    t = TERRAIN_PARAMS[kind]
    for p, end, is_int in zip(t.names, t.hard, t.integer):
      names.append(f"{kind}.{p}")
      low.append(float(ranges[kind][p][0]))
      high.append(float(ranges[kind][p][1]))
      integer.append(is_int)
      hard.append(end)
  return Ranges(tuple(names), tuple(low), tuple(high), tuple(integer), tuple(hard))


@dataclasses.dataclass(frozen=True)
class TerrainScene:
  """Episodes on terrains of the given kinds (one drawn per episode, each with probability
  1 / len(kinds)); xi holds every kind's parameters (terrain_ranges), `variant` the kind's index."""

  kinds: tuple[str, ...]
  sampler: str  # scenes.samplers.SAMPLERS
  variant: str  # incremental variant (scenes.samplers.VARIANTS)
  ranges: Ranges  # terrain_ranges(kinds, ...)
  random_spawn: bool
  random_goal: bool

  def __post_init__(self):
    unknown = [k for k in self.kinds if k not in TERRAIN_PARAMS]
    if not self.kinds or unknown:
      raise ValueError(f"terrain kinds must be a non-empty list of {sorted(TERRAIN_PARAMS)}, got {list(self.kinds)}")
    corridor_world(self.kinds)

  @property
  def corridor(self) -> bool:
    """Whether the world has the corridor's side walls (every kind but the spirals)."""
    return corridor_world(self.kinds)

  n_boxes = POOL

  def world_xml(self) -> str:
    return world_xml(POOL, walls=self.corridor)

  def offsets(self) -> np.ndarray:
    """Where each kind's parameters start in xi."""
    return np.cumsum([0] + [len(TERRAIN_PARAMS[k].names) for k in self.kinds])

  def layout(self, kind: jax.Array, xi: jax.Array, key: jax.Array):
    """Boxes and Ends of terrain kind index `kind` (a traced int) from the whole xi."""
    off = self.offsets()
    branches = [lambda xi, key, i=i, k=k: LAYOUTS[k](xi[off[i]:off[i + 1]], key)
                for i, k in enumerate(self.kinds)]
    return jax.lax.switch(kind, [lambda xi, key, b=b: _flat(*b(xi, key)) for b in branches], xi, key)

  def sample(self, key: jax.Array, eps: jax.Array, draw: samplers.Draw | None = None) -> SceneState:
    """Draws the kind and xi (from the draw, if given: its sampler, ranges and the kinds it allows),
    lays the terrain out, the spawn (ground point, yaw) and the goal."""
    k_kind, k_xi, k_layout, *k_ends = jax.random.split(key, 7)
    kind = samplers.pick_kind(k_kind, len(self.kinds), draw)  # kind ~ U{kinds (the draw's)}
    xi = samplers.sample(k_xi, eps, self.ranges, self.sampler, self.variant, draw)
    pos, size, box_yaw, e = self.layout(kind, xi, k_layout)
    ahead = jnp.where(e.yaw == 0.0, 1.0, -1.0)
    spawn, yaw, goal = randomized_ends(k_ends, e.spawn, e.yaw, e.goal, ahead, self.random_spawn, self.random_goal)
    halfwidth = jnp.float32(0.0) if self.random_goal else e.goal_halfwidth
    return SceneState(pos, size, box_yaw, spawn, yaw, goal, halfwidth, xi, kind.astype(jnp.int32))


def _flat(pos, size, yaw, ends: Ends):
  """lax.switch branches must return arrays of one structure and dtype."""
  f = lambda a: jnp.asarray(a, jnp.float32)  # noqa: E731
  return f(pos), f(size), f(yaw), jax.tree.map(f, ends)

"""2D navigation: hallway or zigzag (each with probability 1/2) with two wall obstacles.

Area: x in [0, A] m with A = 12 (scene.nav_length; start area [0, 2], obstacle area [2, A - 2],
goal area [A - 2, A]), y in [-W/2, W/2] with W = 10 m, closed by four wall planes.
xi = (W1, L1, W2, L2, C), with the gap C ~ U(C_min, C_max) (scene.nav_gap; the original's
U(1, 2) m, 1 + U(0, 1)):
  hallway: obstacle 1 juts W1 ~ U(W/2 - C/2, W - C) from the left wall, obstacle 2 juts
           W2 ~ U(0, W - C - W1) from the right wall, so the hallway between them is >= C wide;
           both run L_i ~ U(L/2, L) along x (L = A - 4 m) from random points of the obstacle area.
  zigzag:  two thin walls across the corridor, obstacle 1 from the left wall at x = 2 + L/3,
           obstacle 2 from the right wall at x = 2 + 2L/3, each W_i ~ U(W/2 - C/2, W - C)
           long, so the robot must weave; L_i is their thickness (0.3 m).
Components are drawn as u in [0, 1]^5 by the scene's sampler (uniform or incremental over unit
ranges) and mapped onto those intervals. Spawn: fixed (1, 0) facing +x, or random x ~ U(0.8, 1.2),
y ~ U(-4, 4), yaw ~ U(-pi/2, pi/2): every spawn is >= 0.8 m from the walls and the obstacle area
(x >= 2 m), so a robot that cannot reverse can always turn in place (the circle robot 1 sweeps:
0.62 m at rest, 0.75 m with its arm stretched flat ahead; x ~ U(0.75, 1.5) until 2026-11-25 put
3 % of the hallway spawns within 0.75 m of an obstacle, some facing into it). Goal: fixed (A - 1, 0),
or random x ~ U(A - 1.5, A - 0.5), y ~ U(-4, 4) (with A = 12: (11, 0), U(10.5, 11.5)).
Floor obstacles (`floor_obstacles` of them): low boxes to drive over or around, each
centred at x ~ U(2.5, A - 2.5), y ~ U(-4.5, 4.5) m, FLOOR_SIDE ~ U(0.3, 0.8) m along and across, and
height ~ U(h_min, h_max) (`floor_height`); drawn per episode, kept in the scene's box arrays. With
`floor_passage` = p > 0 (scene.nav_floor_passage) the layout is conditioned on a way round: up to
FLOOR_TRIES layouts are drawn and the first with a free-space path from the spawn to the goal
around the wall and floor obstacles, for a disc of radius min(p, C / 2 - GAP_MARGIN), is kept;
where none has one (1.5 % of 4,000 scenes at p = 0.5 m, 5.4 % at 0.62: results/nav/floor-turn-passage*-cpu.json),
the floor obstacles are left out of that scene (parked off the area). Without it (p = 0) 12 % of the scenes with 6 obstacles have no way round for a disc
of robot 1's half-width (scripts/analysis/nav_floor_blocking.py): the robot must cross a box.
Free-space distance (episode.distance: geodesic): the shortest path to the goal around the two wall
obstacles keeping r = min(scene.nav_clearance, C / 2 - GAP_MARGIN) from them and from the walls
(scenes.geodesic; r = 0.4 m, robot 1's half-width, follows corners as tightly as the robot's width
allows; 0.75 m, its half-diagonal, leaves room for its ends to swing round a corner); floor obstacles can be driven over, so
they do not lengthen it. Collisions (episode / reward settings): any robot contact with a wall or a
wall obstacle, or a contact of anything but a track belt with a floor obstacle (NavScene.collision_geoms).
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp

from scenes import samplers
from scenes.clearance import footprint_clearance
from scenes.geodesic import geodesic_distance
from scenes.samplers import Ranges
from scenes.scene import SceneState
from scenes.world import PARKED_HALF, SCENE_BOX, parked_box_xml, parked_xyz, world_geom_attrs

AREA_W = 10.0  # m, W
START_X, AREA_LEN = 2.0, 12.0  # m: where the obstacle area starts, the area's length A (default)
NAV_LENGTH_LIMITS = (AREA_LEN, 30.0)  # m, what scene.nav_length may ask
NAV_GAP_LIMITS = (0.85, 3.0)  # m, what scene.nav_gap may ask: robot 1 is 0.81 m wide
WALL_THICKNESS = 0.3  # m, zigzag walls
OBSTACLE_HEIGHT = 1.0  # m
FLOOR_Y, FLOOR_SIDE = (-AREA_W / 2 + 0.5, AREA_W / 2 - 0.5), (0.3, 0.8)  # m (x: NavScene.floor_x)
MAX_FLOOR_OBSTACLES = 12
FLOOR_TRIES = 4  # floor layouts drawn per scene where a way round them is asked for (floor_passage)
NAV_FLOOR_PASSAGE_LIMITS = (0.0, 1.0)  # m, what scene.nav_floor_passage may ask (0: no condition)
WALL_OBSTACLES = 2  # the first scene boxes: the hallway's or zigzag's obstacles; floor obstacles follow
WALLS = ("wall_left", "wall_right", "wall_back", "wall_front")  # the area's wall planes (geom names)
NAV_CLEARANCE_LIMITS = (0.3, 1.0)  # m, what scene.nav_clearance may ask (robot 1: half-width 0.39, half-diagonal 0.75)
GAP_MARGIN = 0.02  # m, a path through a gap C keeps at most C / 2 - GAP_MARGIN from its sides
SPAWN_X = (0.8, 1.2)  # m, random spawns' x range (module docstring: room to turn in place)
SPAWN_Y = (-4.0, 4.0)  # m, random spawns' y range
AREA_LO, AREA_HI = (0.0, -AREA_W / 2), (AREA_LEN, AREA_W / 2)  # m, the default area's corners (x, y)
NAV_AREAS = ("hallway", "zigzag")  # the area kinds (scene.nav_kinds)
UNIT = Ranges(names=("W1", "L1", "W2", "L2", "C"), low=(0.0,) * 5, high=(1.0,) * 5,
              integer=(False,) * 5, hard=("high", "high", "high", "high", "low"))
# hardest: obstacles jutting furthest and longest, the narrowest gap C


def gap_capped(r, gap):
  """A path's distance from walls and obstacles (m), at most what the area's gap C allows."""
  return jnp.minimum(r, gap / 2 - GAP_MARGIN)


def area_corners(length: float = AREA_LEN) -> tuple[jax.Array, jax.Array]:
  """(lo, hi) m: the corners (x, y) of the area of this length (m), inside its wall planes."""
  return jnp.array(AREA_LO), jnp.array((length, AREA_HI[1]))


def path_around(start, goal, box_pos, box_size, r, length: float = AREA_LEN):
  """Length (m; inf: none) of the shortest path from start to goal (x, y) in the area of this length
  (m) around the boxes (centres and half-sizes, (k, 2) m), keeping r (m) from them and from the walls
  (scenes.geodesic)."""
  return geodesic_distance(start, goal, box_pos - box_size, box_pos + box_size, *area_corners(length), r)


def _lerp(a, b, u):
  return a + (b - a) * u


@dataclasses.dataclass(frozen=True)
class NavScene:
  """Hallway / zigzag navigation area."""

  sampler: str  # scenes.samplers.SAMPLERS
  variant: str  # incremental variant (scenes.samplers.VARIANTS)
  kinds: tuple[str, ...]  # of ("hallway", "zigzag"), drawn with equal probability
  random_spawn: bool
  random_goal: bool
  floor_obstacles: int  # low boxes in the obstacle area (0..MAX_FLOOR_OBSTACLES)
  floor_height: tuple[float, float]  # m, their height ~ U(min, max)
  gap: tuple[float, float]  # m, C ~ U(min, max)
  clearance: float  # m, the free-space path's distance from walls and obstacles (module docstring)
  floor_passage: float = 0.0  # m, radius of the disc that must find a way round the floor obstacles (0: none asked)
  length: float = AREA_LEN  # m, the area's length A along x

  @property
  def obstacle_length(self) -> float:
    """L (m): the obstacle area's length."""
    return self.length - 2 * START_X

  @property
  def floor_x(self) -> tuple[float, float]:
    """m, the range of the floor obstacles' centres along x."""
    return START_X + 0.5, self.length - START_X - 0.5

  def __post_init__(self):
    if not self.kinds or any(k not in NAV_AREAS for k in self.kinds):
      raise ValueError(f"nav kinds must be a non-empty subset of {NAV_AREAS}, got {self.kinds}")
    if not 0 <= self.floor_obstacles <= MAX_FLOOR_OBSTACLES:
      raise ValueError(f"floor obstacles must number 0..{MAX_FLOOR_OBSTACLES}, got {self.floor_obstacles}")

  direction = "flat"

  def world_xml(self) -> str:
    w = world_geom_attrs()
    h = AREA_W / 2
    boxes = "\n".join(parked_box_xml(k, ".6 .4 .3 1") for k in range(2 + self.floor_obstacles))
    return f"""
    <geom name="floor" type="plane" size="0 0 1" {w} rgba=".5 .55 .5 1"/>
    <geom name="wall_left" type="plane" pos="0 {h} 0" zaxis="0 -1 0" size="0 0 1" {w} rgba=".6 .6 .7 .3"/>
    <geom name="wall_right" type="plane" pos="0 {-h} 0" zaxis="0 1 0" size="0 0 1" {w} rgba=".6 .6 .7 .3"/>
    <geom name="wall_back" type="plane" pos="0 0 0" zaxis="1 0 0" size="0 0 1" {w} rgba=".6 .6 .7 .3"/>
    <geom name="wall_front" type="plane" pos="{self.length} 0 0" zaxis="-1 0 0" size="0 0 1" {w} rgba=".6 .6 .7 .3"/>
    {boxes}"""

  def sample(self, key: jax.Array, eps: jax.Array, draw: samplers.Draw | None = None) -> SceneState:
    """Draws the area and its layout (with a draw: its sampler and the areas it allows)."""
    k_kind, k_u, k_x, k_s, k_g = jax.random.split(key, 5)
    kinds = jnp.array([{"hallway": 0, "zigzag": 1}[k] for k in self.kinds])
    variant = kinds[samplers.pick_kind(k_kind, len(self.kinds), draw)]
    u = samplers.sample(k_u, eps, UNIT, self.sampler, self.variant, draw)
    c = _lerp(*self.gap, u[4])
    w1 = _lerp(AREA_W / 2 - c / 2, AREA_W - c, u[0])
    half_w = AREA_W / 2
    # hallway
    w2_h = _lerp(0.0, AREA_W - c - w1, u[2])
    big_l = self.obstacle_length
    l1, l2 = _lerp(big_l / 2, big_l, u[1]), _lerp(big_l / 2, big_l, u[3])
    x1 = START_X + jax.random.uniform(k_x, (2,)) * (big_l - jnp.stack([l1, l2]))
    hall_pos = jnp.array([[x1[0] + l1 / 2, half_w - w1 / 2, 0.0], [x1[1] + l2 / 2, -half_w + w2_h / 2, 0.0]])
    hall_size = jnp.array([[l1 / 2, w1 / 2, 0.0], [l2 / 2, w2_h / 2, 0.0]])
    # zigzag
    w2_z = _lerp(AREA_W / 2 - c / 2, AREA_W - c, u[2])
    zig_pos = jnp.array([[START_X + big_l / 3, half_w - w1 / 2, 0.0],
                         [START_X + 2 * big_l / 3, -half_w + w2_z / 2, 0.0]])
    zig_size = jnp.array([[WALL_THICKNESS / 2, w1 / 2, 0.0], [WALL_THICKNESS / 2, w2_z / 2, 0.0]])
    zig = variant == 1
    pos = jnp.where(zig, zig_pos, hall_pos).at[:, 2].set(OBSTACLE_HEIGHT / 2)
    size = jnp.where(zig, zig_size, hall_size).at[:, 2].set(OBSTACLE_HEIGHT / 2)
    size = jnp.maximum(size, 1e-3)  # a zero-width obstacle stays a valid box
    xi = jnp.stack([w1, jnp.where(zig, WALL_THICKNESS, l1), jnp.where(zig, w2_z, w2_h),
                    jnp.where(zig, WALL_THICKNESS, l2), c])
    s = jax.random.uniform(k_s, (3,))
    if self.random_spawn:
      spawn, yaw = jnp.array([_lerp(*SPAWN_X, s[0]), _lerp(*SPAWN_Y, s[1]), 0.0]), _lerp(-jnp.pi / 2, jnp.pi / 2, s[2])
    else:
      spawn, yaw = jnp.array([1.0, 0.0, 0.0]), jnp.float32(0.0)
    g = jax.random.uniform(k_g, (2,))
    a = self.length
    goal = (jnp.array([_lerp(a - 1.5, a - 0.5, g[0]), _lerp(-4.0, 4.0, g[1]), 0.085]) if self.random_goal
            else jnp.array([a - 1.0, 0.0, 0.085]))
    if self.floor_obstacles:
      f_pos, f_size = self.passable_floor(key, pos[:, :2], size[:, :2], spawn, goal, c)
      pos, size = jnp.concatenate([pos, f_pos]), jnp.concatenate([size, f_size])
    return SceneState(pos, size, jnp.zeros(pos.shape[0]), spawn, yaw, goal, jnp.float32(0.0), xi, variant.astype(jnp.int32))

  def passable_floor(self, key, wall_pos, wall_size, spawn, goal, gap) -> tuple[jax.Array, jax.Array]:
    """The floor obstacles' centres and half-sizes (m): the first draw, or with floor_passage the
    first of FLOOR_TRIES draws with a way round (module docstring), else none (parked off the area)."""
    if not self.floor_passage:
      return self.floor_boxes(jax.random.fold_in(key, 1))
    f_pos, f_size = jax.vmap(lambda j: self.floor_boxes(jax.random.fold_in(key, 1 + j)))(jnp.arange(FLOOR_TRIES))
    r = gap_capped(self.floor_passage, gap)

    def way_round(fp, fs):
      return jnp.isfinite(path_around(spawn[:2], goal[:2], jnp.concatenate([wall_pos, fp[:, :2]]),
                                      jnp.concatenate([wall_size, fs[:, :2]]), r, self.length))
    ok = jax.vmap(way_round)(f_pos, f_size)
    pick = jnp.argmax(ok)  # the first draw with a way round (0 where none has one)
    parked = jnp.array([parked_xyz(WALL_OBSTACLES + i) for i in range(self.floor_obstacles)], jnp.float32)
    keep = jnp.any(ok)
    return jnp.where(keep, f_pos[pick], parked), jnp.where(keep, f_size[pick], jnp.full_like(f_size[0], PARKED_HALF))

  def collision_geoms(self) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """(geoms no part of the robot may touch, geoms only the track belts may touch): the walls and
    wall obstacles; the floor obstacles (driven over on the belts)."""
    boxes = [f"{SCENE_BOX}{k}" for k in range(WALL_OBSTACLES + self.floor_obstacles)]
    return WALLS + tuple(boxes[:WALL_OBSTACLES]), tuple(boxes[WALL_OBSTACLES:])

  def free_space_distance(self, scene: SceneState, pos: jax.Array, boxes: int = WALL_OBSTACLES,
                          clearance: float | None = None) -> jax.Array:
    """Length (m) of the shortest path from pos (x, y, ...) to the goal around the wall obstacles
    (module docstring); around the first `boxes` scene boxes (WALL_OBSTACLES + floor_obstacles: the
    floor obstacles too) and keeping `clearance` (m, default scene.nav_clearance) where given, the
    clearance capped alike."""
    wanted = self.clearance if clearance is None else clearance
    return path_around(pos[:2], scene.goal[:2], scene.box_pos[:boxes, :2], scene.box_size[:boxes, :2],
                       gap_capped(wanted, scene.xi[4]), self.length)  # xi[4]: this area's gap C

  def wall_clearance(self, scene: SceneState, pos: jax.Array, yaw: jax.Array, half: jax.Array) -> jax.Array:
    """() m: distance from the robot's footprint (centre pos (x, y, ...), yaw rad, half-sizes half
    (2,) m) to the nearest wall or wall obstacle (scenes.clearance); floor obstacles are driven over."""
    box = scene.box_pos[:WALL_OBSTACLES, :2], scene.box_size[:WALL_OBSTACLES, :2]
    return footprint_clearance(pos[:2], yaw, half, box[0] - box[1], box[0] + box[1], *area_corners(self.length))

  def floor_boxes(self, key: jax.Array) -> tuple[jax.Array, jax.Array]:
    """Centres and half-sizes (floor_obstacles, 3) of the floor obstacles (m; distributions in the
    module docstring)."""
    u = jax.random.uniform(key, (self.floor_obstacles, 5))
    height = _lerp(*self.floor_height, u[:, 4])
    pos = jnp.stack([_lerp(*self.floor_x, u[:, 0]), _lerp(*FLOOR_Y, u[:, 1]), height / 2], axis=-1)
    size = jnp.stack([_lerp(*FLOOR_SIDE, u[:, 2]) / 2, _lerp(*FLOOR_SIDE, u[:, 3]) / 2, height / 2], axis=-1)
    return pos, size

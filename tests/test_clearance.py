"""The footprint's clearance (scenes.clearance) against an exact plain-Python polygon distance, hand
cases, and the reward term it feeds (mjx_tracks.envs.rewards)."""

import dataclasses
import math
import random

import jax
import jax.numpy as jnp
import pytest

from mjx_tracks.envs.config import ConfigError, default_config, load_config
from mjx_tracks.envs.rewards import Monitor
from scenes.clearance import footprint_clearance, rectangle_corners

AREA_LO, AREA_HI = (0.0, -5.0), (12.0, 5.0)  # m, far from every case below but the wall cases


def _segment_point(a, b, p) -> float:
  (ax, ay), (bx, by), (px, py) = a, b, p
  dx, dy = bx - ax, by - ay
  t = max(0.0, min(1.0, ((px - ax) * dx + (py - ay) * dy) / (dx * dx + dy * dy)))
  return math.hypot(ax + t * dx - px, ay + t * dy - py)


def _cross(o, a, b) -> float:
  return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])


def _segments_cross(a, b, c, d) -> bool:
  return _cross(a, b, c) * _cross(a, b, d) < 0 and _cross(c, d, a) * _cross(c, d, b) < 0


def _inside(p, poly) -> bool:
  """p inside the convex polygon (corners in order)."""
  signs = [_cross(poly[i], poly[(i + 1) % len(poly)], p) for i in range(len(poly))]
  return all(s > 0 for s in signs) or all(s < 0 for s in signs)


def _polygon_distance(p, q) -> float:
  """Exact distance (m) between two convex polygons (corners in order): 0 where they overlap, else
  the least distance between their edges."""
  edges = lambda poly: [(poly[i], poly[(i + 1) % len(poly)]) for i in range(len(poly))]
  if any(_inside(v, q) for v in p) or any(_inside(v, p) for v in q):
    return 0.0
  if any(_segments_cross(a, b, c, d) for a, b in edges(p) for c, d in edges(q)):
    return 0.0
  return min(min(_segment_point(c, d, v) for v in p for c, d in edges(q)),
             min(_segment_point(a, b, v) for v in q for a, b in edges(p)))


def _in_order(corners):
  """rectangle_corners' order (--, -+, +-, ++) as a polygon's order."""
  return [tuple(map(float, corners[i])) for i in (0, 1, 3, 2)]


def test_the_distance_to_boxes_equals_the_exact_polygon_distance():
  rng = random.Random(0)
  compared = crossing = 0
  for _ in range(300):
    centre = jnp.array([rng.uniform(4, 8), rng.uniform(-1, 1)])
    yaw, half = rng.uniform(-math.pi, math.pi), jnp.array([rng.uniform(0.2, 0.7), rng.uniform(0.2, 0.5)])
    lo = jnp.array([[rng.uniform(3, 8), rng.uniform(-2, 1)] for _ in range(2)])
    hi = lo + jnp.array([[rng.uniform(0.1, 2), rng.uniform(0.1, 2)] for _ in range(2)])
    got = float(footprint_clearance(centre, jnp.float32(yaw), half, lo, hi, jnp.array(AREA_LO), jnp.array(AREA_HI)))
    robot = _in_order(rectangle_corners(centre, jnp.float32(yaw), half))
    boxes = [[(float(a[0]), float(a[1])), (float(a[0]), float(b[1])), (float(b[0]), float(b[1])), (float(b[0]), float(a[1]))]
             for a, b in zip(lo, hi)]
    want = min(_polygon_distance(robot, box) for box in boxes)
    corner_inside = any(_inside(v, box) for box in boxes for v in robot) or any(_inside(v, robot) for box in boxes for v in box)
    if want == 0.0 and not corner_inside:
      crossing += 1  # crossed like a plus sign (module docstring): the corners' distance is read
      continue
    assert got == pytest.approx(want, abs=2e-5)
    compared += 1
  assert compared > 250 and crossing < 10


def test_the_distance_to_the_area_walls_hand_cases():
  none = jnp.zeros((0, 2))
  clear = lambda x, y, yaw: float(footprint_clearance(jnp.array([x, y]), jnp.float32(yaw), jnp.array([0.6, 0.4]),
                                                      none, none, jnp.array(AREA_LO), jnp.array(AREA_HI)))
  assert clear(1.0, 0.0, 0.0) == pytest.approx(0.4)  # back wall x = 0, half-length 0.6
  assert clear(1.0, 0.0, math.pi / 2) == pytest.approx(0.6, abs=1e-6)  # turned: the half-width faces it
  assert clear(6.0, 4.5, 0.0) == pytest.approx(0.1)  # the left wall y = 5, half-width 0.4
  d = math.hypot(0.6, 0.4) * math.sin(math.pi / 4 + math.atan2(0.4, 0.6))  # a corner's reach at 45 degrees
  assert clear(6.0, 4.0, math.pi / 4) == pytest.approx(1.0 - d, abs=1e-6)
  assert clear(11.9, 0.0, 0.0) == 0.0  # through the front wall x = 12


def test_the_clearance_term_pays_in_proportion_to_the_margin_lost():
  reward = dataclasses.replace(default_config().reward, clearance_penalty=0.2, clearance_margin=0.15)
  mon = Monitor(reward, default_config().episode)
  args = (jnp.float32(1.5), jnp.float32(2.0), jnp.float32(2.0), jnp.zeros(3), jnp.float32(0.0), jnp.float32(1.0),
          jnp.bool_(False))
  for clearance, want in ((0.05, -0.2 * 2 / 3), (0.0, -0.2), (0.15, 0.0), (1.0, 0.0), (math.inf, 0.0)):
    terms = mon.evaluate(*args, jnp.float32(clearance))[0]
    assert float(terms["clearance"]) == pytest.approx(want, abs=1e-7), clearance
  assert float(Monitor(default_config().reward, default_config().episode).evaluate(*args, jnp.float32(0.0))[0]["clearance"]) == 0.0


def test_the_env_reads_its_kinds_clearance_only_where_the_term_is_on():
  """TrackedRobotEnv._clearance (what step hands the monitor): the nav kind's clearance of the
  footprint with the term on, inf (no term) with it off; the clearances eager (the scene's draw one
  program: eager, its ~150 operations compile one by one)."""
  import mjx_tracks  # noqa: PLC0415
  on = mjx_tracks.load("nav-obstacles", ["reward.clearance_penalty=0.5", "scene.nav_floor_obstacles=1"])
  off = mjx_tracks.load("nav-obstacles", ["scene.nav_floor_obstacles=1"])
  scene = jax.jit(on.scene.sample)(jax.random.PRNGKey(1), 1.0)
  pos, yaw = jnp.array([1.0, 0.0, 0.2]), jnp.float32(0.0)  # 1 m from the back wall; obstacles from x = 2 m
  got = float(on._clearance(pos, yaw, scene))
  want = float(on.kind.clearance(on.scene, scene, pos, yaw, jnp.array(on.footprint)))
  assert got == want == pytest.approx(1.0 - 0.505, abs=1e-5)  # the flipper tips (0.505 m) from the back wall
  assert float(off._clearance(pos, yaw, scene)) == math.inf


def test_a_clearance_penalty_where_nothing_measures_it_is_refused_naming_the_key():
  with pytest.raises(ConfigError, match="reward.clearance_penalty"):
    load_config("asc-inc-cog", ["reward.clearance_penalty=0.1"])


def test_the_riding_term_charges_a_step_that_ends_on_a_floor_obstacle():
  """reward.riding_penalty per step whose physics ended with a belt on a floor obstacle (the watch's
  riding flag: test_collisions.py checks it against the C engine); 0 where off; refused on stairs."""
  reward = dataclasses.replace(default_config().reward, riding_penalty=0.05)
  args = (jnp.float32(1.5), jnp.float32(2.0), jnp.float32(2.0), jnp.zeros(3), jnp.float32(0.0), jnp.float32(1.0),
          jnp.bool_(False), math.inf)
  mon = Monitor(reward, default_config().episode)
  assert float(mon.evaluate(*args, jnp.bool_(True))[0]["riding"]) == pytest.approx(-0.05)
  assert float(mon.evaluate(*args, jnp.bool_(False))[0]["riding"]) == 0.0
  assert float(Monitor(default_config().reward, default_config().episode).evaluate(*args, jnp.bool_(True))[0]["riding"]) == 0.0
  with pytest.raises(ConfigError, match="reward.riding_penalty"):
    load_config("asc-inc-cog", ["reward.riding_penalty=0.1"])

"""The free-space distance (scenes.geodesic) against paths computed by hand, and the navigation
area's use of it."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from mjx_tracks.envs.config import load_config
from mjx_tracks.envs.task_env import make_scene
from scenes.geodesic import NODE_OFFSET, geodesic_distance, segment_blocked
from scenes.navigation import AREA_HI, AREA_LO, GAP_MARGIN, WALL_OBSTACLES
from scenes.scene import SceneState

AREA = jnp.array(AREA_LO), jnp.array(AREA_HI)  # x in [0, 12], y in [-5, 5] m
R = 0.4  # m, clearance of the hand-computed cases
# a wall from the right side wall up to y = 3, x in [4, 5]: the way round is through y in (3, 5)
WALL_LO, WALL_HI = jnp.array([[4.0, -5.0]]), jnp.array([[5.0, 3.0]])
TOL = 4 * NODE_OFFSET + 1e-4  # m: corners sit NODE_OFFSET off the inflated box


_geodesic = jax.jit(geodesic_distance)  # one program per wall count (eager, each operation compiles alone)


def g(p, goal, lo=WALL_LO, hi=WALL_HI, r=R):
  return float(_geodesic(jnp.array(p), jnp.array(goal), lo, hi, *AREA, jnp.float32(r)))


def test_a_clear_line_is_the_straight_distance():
  assert g([1.0, 4.0], [8.0, 4.0]) == pytest.approx(7.0, abs=1e-5)  # above the wall's inflated top (3.4)


def test_around_a_wall_the_path_runs_over_its_inflated_corners():
  # (1, 0) -> (3.6, 3.4) -> (5.4, 3.4) -> (8, 0): two 2.6 x 3.4 legs and the 1.8 m top of the inflated wall
  assert g([1.0, 0.0], [8.0, 0.0]) == pytest.approx(2 * math.hypot(2.6, 3.4) + 1.8, abs=TOL)


def test_two_walls_make_a_zigzag():
  # a second wall from the left side wall down to y = -3, x in [7, 8]: (1, 0) -> (3.6, 3.4) -> (5.4, 3.4)
  # -> (6.6, -3.4) -> (8.4, -3.4) -> (11, 0)
  lo, hi = jnp.array([[4.0, -5.0], [7.0, -3.0]]), jnp.array([[5.0, 3.0], [8.0, 5.0]])
  want = math.hypot(2.6, 3.4) + 1.8 + math.hypot(1.2, 6.8) + 1.8 + math.hypot(2.6, 3.4)
  assert g([1.0, 0.0], [11.0, 0.0], lo, hi) == pytest.approx(want, abs=2 * TOL)


def test_a_closed_area_has_no_path_and_the_robot_touching_a_wall_still_has_one():
  assert math.isinf(g([1.0, 0.0], [8.0, 0.0], WALL_LO, jnp.array([[5.0, 5.0]])))  # the wall spans the width
  # the robot within the clearance of the wall (not inside it): round the near inflated corner
  assert g([4.5, 3.2], [8.0, 0.0]) == pytest.approx(math.hypot(0.9, 0.2) + math.hypot(2.6, 3.4), abs=TOL)


def test_the_distance_falls_fastest_along_the_path_so_its_gradient_steers():
  """-grad G is the unit vector toward the goal in the open and toward the inflated corner the path
  runs over behind the wall (scripts/analysis/nav_scripted.py steers by it)."""
  grad = lambda p, goal: np.asarray(jax.grad(lambda q: geodesic_distance(  # noqa: E731
      q, jnp.array(goal), WALL_LO, WALL_HI, *AREA, R))(jnp.array(p)))
  np.testing.assert_allclose(-grad([1.0, 4.0], [8.0, 4.0]), [1.0, 0.0], atol=1e-5)
  corner = np.array([4.0 - R, 3.0 + R])  # the path (1, 0) -> (3.6, 3.4) -> ...
  want = (corner - [1.0, 0.0]) / np.linalg.norm(corner - [1.0, 0.0])
  np.testing.assert_allclose(-grad([1.0, 0.0], [8.0, 0.0]), want, atol=1e-3)


def test_the_slab_test_lets_segments_graze_a_box_but_not_cross_it():
  lo, hi = jnp.array([[0.0, 0.0]]), jnp.array([[1.0, 1.0]])
  assert not segment_blocked(jnp.array([-1.0, 1.0]), jnp.array([2.0, 1.0]), lo, hi)  # along the top edge
  assert not segment_blocked(jnp.array([-1.0, 2.0]), jnp.array([2.0, 2.0]), lo, hi)
  assert segment_blocked(jnp.array([-1.0, 0.5]), jnp.array([2.0, 0.5]), lo, hi)
  assert not segment_blocked(jnp.array([-1.0, 0.5]), jnp.array([-0.5, 0.5]), lo, hi)  # ends before it
  assert segment_blocked(jnp.array([0.5, 2.0]), jnp.array([0.5, 0.5]), lo, hi)  # ends inside it


@pytest.mark.parametrize("clearance, gap, r", [(0.4, 2.0, 0.4), (0.75, 2.0, 0.75), (0.75, 1.0, 0.5 - GAP_MARGIN)])
def test_navigation_areas_use_their_wall_obstacles_and_the_path_clearance(clearance, gap, r):
  """r = min(scene.nav_clearance, C / 2 - GAP_MARGIN), C = xi[4], the area's gap."""
  scene = make_scene(load_config("nav-obstacles", [f"scene.nav_clearance={clearance}"]).scene)
  pos = jnp.array([[4.5, 1.0, 0.5], [7.5, -1.0, 0.5]] + [[6.0, 0.0, 0.05]] * scene.floor_obstacles)
  size = jnp.array([[0.5, 4.0, 0.5], [0.5, 4.0, 0.5]] + [[5.0, 5.0, 0.05]] * scene.floor_obstacles)  # floor: no effect
  s = SceneState(pos, size, jnp.zeros(len(pos)), jnp.array([1.0, 0.0, 0.0]), jnp.float32(0.0),
                 jnp.array([11.0, 0.0, 0.085]), jnp.float32(0.0), jnp.array([0.0, 0.0, 0.0, 0.0, gap]), jnp.int32(1))
  lo, hi = pos[:WALL_OBSTACLES, :2] - size[:WALL_OBSTACLES, :2], pos[:WALL_OBSTACLES, :2] + size[:WALL_OBSTACLES, :2]
  want = g([1.0, 0.0], [11.0, 0.0], lo, hi, r)
  assert float(scene.free_space_distance(s, s.spawn_pos)) == pytest.approx(want, abs=1e-5)
  assert want > 10.0 + 2.0  # the zigzag is longer than the straight line


@pytest.mark.parametrize("clearance", [0.4, 0.75])
def test_the_free_space_distance_is_never_shorter_than_the_straight_line(clearance):
  scene = make_scene(load_config("nav", [f"scene.nav_clearance={clearance}", "scene.nav_gap=[0.85,2.0]"]).scene)

  def both(key):
    s = scene.sample(key, jnp.float32(1.0))
    return scene.free_space_distance(s, s.spawn_pos), jnp.linalg.norm(s.spawn_pos[:2] - s.goal[:2])

  geo, straight = map(np.asarray, jax.jit(jax.vmap(both))(jax.random.split(jax.random.PRNGKey(0), 500)))
  assert np.isfinite(geo).all()  # every drawn area leaves a way through
  assert (geo >= straight - 1e-4).all() and (geo > straight + 0.5).mean() > 0.3


def test_a_goal_within_the_clearance_of_an_obstacle_is_still_reached():
  """The goal 0.3 m right of the wall's face (x = 5.3), inside its 0.4 m inflation: the path runs
  round the inflated wall to the corner (5.4, 3.4) and from there straight to the goal, seen past
  the wall as it is (not inflated)."""
  corner = (5.0 + R, 3.0 + R)
  want = math.dist((1.0, 0.0), (4.0 - R, 3.0 + R)) + 1.0 + 2 * R + math.dist(corner, (5.3, 0.0))
  assert g([1.0, 0.0], [5.3, 0.0]) == pytest.approx(want, abs=TOL)

"""scripts/analysis/nav_collision_sites.py's geometry against hand-computed distances."""

import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "scripts", "analysis"))
from nav_collision_sites import REACH_SLACK, footprint_distance, reaches  # noqa: E402

import mjx_tracks  # noqa: E402
from mjx_tracks.robots.jaguar import JAGUAR  # noqa: E402


def test_the_distance_to_a_box_footprint_is_zero_inside_and_the_gap_outside():
  centre, half = np.array([[[2.0, 1.0]]]), np.array([[[0.5, 0.2]]])  # x in [1.5, 2.5], y in [0.8, 1.2]
  points = np.array([[2.2, 1.1], [3.0, 1.0], [2.0, 0.5], [3.5, 2.2]])
  d = footprint_distance(points, np.repeat(centre, 4, 0), np.repeat(half, 4, 0), np.zeros((4, 1)))
  np.testing.assert_allclose(d[:, 0], [0.0, 0.5, 0.3, np.hypot(1.0, 1.0)], atol=1e-12)
  # turned a quarter: x in [1.8, 2.2], y in [0.5, 1.5]
  d = footprint_distance(points, np.repeat(centre, 4, 0), np.repeat(half, 4, 0), np.full((4, 1), np.pi / 2))
  np.testing.assert_allclose(d[:, 0], [0.0, 0.8, 0.0, np.hypot(1.3, 0.7)], atol=1e-12)


def test_robot_1_reaches_floor_boxes_with_its_belly_alone_and_walls_with_its_flippers():
  body, robot = reaches(mjx_tracks.load("nav-obstacles"))  # robot 1
  belly, flipper = JAGUAR.belly, JAGUAR.flippers[0]
  # the belly capsule, centred under the chassis origin: its half-length plus radius
  np.testing.assert_allclose(body, (belly.end - belly.start) / 2 + belly.radius + REACH_SLACK, atol=1e-6)
  # at least a flipper's tip, level and straight out: its last capsule's end and radius past the pivot
  tip = flipper.segments[-1]
  assert robot >= np.hypot(abs(flipper.pivot[0]) + tip.end, abs(flipper.pivot[1])) + REACH_SLACK
  assert robot < 1.0  # a sphere bound, not the whole area

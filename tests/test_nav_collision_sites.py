"""scripts/analysis/nav_collision_sites.py's geometry against hand-computed distances."""

import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "scripts", "analysis"))
from nav_collision_sites import footprint_distance  # noqa: E402


def test_the_distance_to_a_box_footprint_is_zero_inside_and_the_gap_outside():
  centre, half = np.array([[[2.0, 1.0]]]), np.array([[[0.5, 0.2]]])  # x in [1.5, 2.5], y in [0.8, 1.2]
  points = np.array([[2.2, 1.1], [3.0, 1.0], [2.0, 0.5], [3.5, 2.2]])
  d = footprint_distance(points, np.repeat(centre, 4, 0), np.repeat(half, 4, 0), np.zeros((4, 1)))
  np.testing.assert_allclose(d[:, 0], [0.0, 0.5, 0.3, np.hypot(1.0, 1.0)], atol=1e-12)
  # turned a quarter: x in [1.8, 2.2], y in [0.5, 1.5]
  d = footprint_distance(points, np.repeat(centre, 4, 0), np.repeat(half, 4, 0), np.full((4, 1), np.pi / 2))
  np.testing.assert_allclose(d[:, 0], [0.0, 0.8, 0.0, np.hypot(1.3, 0.7)], atol=1e-12)

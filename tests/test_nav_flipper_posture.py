"""scripts/analysis/nav_flipper_posture.py: the chassis' plane distance to the nearest wall obstacle,
against hand-computed cases (the rollout itself is train.evaluate's trials, tested there)."""

import os
import sys

import jax.numpy as jnp
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "scripts", "analysis"))
from nav_flipper_posture import wall_distance  # noqa: E402

# two boxes: centred (4, 2) with half-sizes (0.15, 3) (a zigzag wall), and (8, -2) with (0.15, 3)
POS = jnp.array([[4.0, 2.0, 0.5], [8.0, -2.0, 0.5]])
SIZE = jnp.array([[0.15, 3.0, 0.5], [0.15, 3.0, 0.5]])


@pytest.mark.parametrize("xy, want", [
    ((4.0, -1.5), 0.5),  # below the first wall's end (y = -1): 0.5 m
    ((5.15, 0.0), 1.0),  # beside its face (x = 4.15): 1 m
    ((4.15 + 0.3, -1.0 - 0.4), 0.5),  # diagonal from its corner (4.15, -1): 3-4-5
    ((4.0, 2.0), 0.0),  # inside it
    ((8.0, 1.5), 0.5),  # above the second wall's end (y = 1): the nearer of the two
])
def test_the_distance_to_the_nearest_wall_obstacle_is_the_hand_computed_one(xy, want):
  assert float(wall_distance(jnp.array(xy), POS, SIZE)) == pytest.approx(want, abs=1e-6)

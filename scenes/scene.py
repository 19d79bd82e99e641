"""What a reset draws for one environment: box geometry, spawn, goal and the parameters xi."""

from __future__ import annotations

import jax
from flax import struct


@struct.dataclass
class SceneState:
  box_pos: jax.Array  # (n_boxes, 3) m, centres of the world's scene boxes
  box_size: jax.Array  # (n_boxes, 3) m, half-sizes
  box_yaw: jax.Array  # (n_boxes,) rad, each box's rotation about z (0: axis-aligned)
  spawn_pos: jax.Array  # (3,) m, ground point under the robot's centre
  spawn_yaw: jax.Array  # () rad
  goal: jax.Array  # (3,) m, centre of the goal segment
  goal_halfwidth: jax.Array  # () m: the goal is the segment goal +- goal_halfwidth along y (0: a point)
  xi: jax.Array  # (k,) sampled scene parameters (names in the scene's Ranges)
  variant: jax.Array  # () int32: 0 stairs / hallway, 1 zigzag


@struct.dataclass
class Ends:
  """Where an episode starts and ends: spawn ground point (m), yaw (rad), goal (m), and the goal's
  half-width along y (m; 0: a point)."""
  spawn: jax.Array
  yaw: jax.Array
  goal: jax.Array
  goal_halfwidth: jax.Array

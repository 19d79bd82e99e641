"""Low-level control: one action vector -> belt speeds and flipper / arm joint targets.

Actions are normalized to [-1, 1] per dimension (NaN -> 0, then clipped) and mapped to:
  v     forward speed, linearly onto [v_min, v_max] m/s
  w     yaw rate, onto [-max_yaw_rate, max_yaw_rate] rad/s
  joint absolute target: onto [lower, upper] limit (rad);
        increment: onto [-INCREMENT, INCREMENT] rad, accumulated into the previous target
Joint targets are always clipped to the joint limits. With a DOF curriculum (`unlock`), an action
dimension acts only once the curriculum's eps reaches its unlock value; until then its joints hold
their previous targets (the paper's conclusion: start with v, w, add flippers, then the arm).
Belt speeds follow the reference's skid-steer relation u = v -+ w S / (2 e) (left, right),
flipper belts as their side, clipped to +-max_speed.
"""

from __future__ import annotations

import dataclasses
import math

import jax
import jax.numpy as jnp
import numpy as np

from mjx_tracks.sim.layout import BELT_SIDE
from mjx_tracks.robots.spec import RobotSpec

INCREMENT = math.pi / 10  # rad per control step, the original's flipper / arm increment

# Action dimensions of each control mode (paper Section 4 and 5); every one but v and w names the
# joint group it drives (robots.spec.JOINT_GROUPS).
CONTROL_MODES: dict[str, tuple[str, ...]] = {
    "4dof": ("v", "w", "front", "rear"),
    "6dof": ("v", "w", "front_left", "front_right", "rear_left", "rear_right"),
    "8dof": ("v", "w", "front_left", "front_right", "rear_left", "rear_right", "arm_1", "arm_2"),
    "5dof_stairs": ("v", "front", "rear", "arm_1", "arm_2"),
    "3dof_stairs": ("v", "front", "rear"),  # a robot without an arm on the stairs (robot 2)
}


@dataclasses.dataclass(frozen=True)
class Controller:
  """Static mapping of one control mode for one robot."""

  mode: str
  dims: tuple[str, ...]
  drive: np.ndarray  # (n_joints, n_action) 0/1: action dim -> joint
  joint_limits: np.ndarray  # (n_joints, 2) rad
  v_range: tuple[float, float]  # m/s
  max_yaw_rate: float  # rad/s
  increments: bool
  track_separation: float  # m
  steering_efficiency: float
  max_speed: float  # m/s
  unlock: np.ndarray  # (n_action,) eps from which each action dimension acts (0: always)

  @staticmethod
  def create(robot: RobotSpec, mode: str, increments: bool = True,
             v_range: tuple[float, float] = (0.0, 1.0),
             dof_curriculum: tuple[tuple[str, float], ...] = ()) -> "Controller":
    """dof_curriculum: (joint action dimension, eps from which it acts) pairs; the others always act."""
    if mode not in CONTROL_MODES:
      raise ValueError(f"unknown control mode {mode!r}; known: {sorted(CONTROL_MODES)}")
    dims = CONTROL_MODES[mode]
    n_joints = len(robot.joint_names())
    if any(d.startswith("arm") for d in dims) and not robot.has_arm:
      raise ValueError(f"control mode {mode!r} drives an arm, but robot {robot.name!r} has none")
    lo, hi = v_range
    if not -robot.max_speed <= lo < hi <= robot.max_speed:
      raise ValueError(f"v_range {v_range} must lie inside +-{robot.max_speed} m/s with min < max")
    drive = np.zeros((n_joints, len(dims)), np.float32)
    for a, name in enumerate(dims):
      if name not in ("v", "w"):
        drive[robot.joint_index(name), a] = 1.0
    return Controller(mode, dims, drive, robot.joint_limits(), tuple(v_range), robot.max_yaw_rate,
                      increments, robot.track_separation, robot.steering_efficiency,
                      robot.max_speed, unlock_values(dims, dof_curriculum))

  @property
  def action_size(self) -> int:
    return len(self.dims)

  def _dim(self, action: jax.Array, name: str, default: float = 0.0) -> jax.Array:
    return action[self.dims.index(name)] if name in self.dims else jnp.asarray(default)

  def decode(self, action: jax.Array, prev_targets: jax.Array,
             eps: jax.Array = 1.0) -> tuple[jax.Array, jax.Array, jax.Array]:
    """Normalized action at curriculum difficulty eps -> (v m/s, w rad/s, joint targets rad)."""
    a = jnp.clip(jnp.where(jnp.isfinite(action), action, 0.0), -1.0, 1.0)
    lo, hi = self.v_range
    v = lo + (self._dim(a, "v", -1.0) + 1.0) * 0.5 * (hi - lo)
    w = self._dim(a, "w") * self.max_yaw_rate
    drive = jnp.asarray(self.drive)
    acting = jnp.asarray(eps) >= jnp.asarray(self.unlock)  # (n_action,)
    driven = drive @ acting.astype(jnp.float32) > 0  # joints of the dimensions that act
    cmd = drive @ a
    lim_lo, lim_hi = jnp.asarray(self.joint_limits[:, 0]), jnp.asarray(self.joint_limits[:, 1])
    if self.increments:
      target = prev_targets + cmd * INCREMENT
    else:
      target = lim_lo + (cmd + 1.0) * 0.5 * (lim_hi - lim_lo)
    target = jnp.where(driven, target, prev_targets)
    return v, w, jnp.clip(target, lim_lo, lim_hi)

  def encode(self, v: jax.Array, w: jax.Array, targets: jax.Array, prev_targets: jax.Array) -> jax.Array:
    """The action that asks for speed v (m/s), yaw rate w (rad/s) and joint targets (rad) from
    prev_targets, as near as one step's action can (clipped to [-1, 1]): decode's inverse, for
    controllers that think in speeds and angles. A joint dimension reads its group's first joint."""
    lo, hi = self.v_range
    cmd = {"v": 2.0 * (v - lo) / (hi - lo) - 1.0, "w": w / self.max_yaw_rate}
    lim_lo, lim_hi = jnp.asarray(self.joint_limits[:, 0]), jnp.asarray(self.joint_limits[:, 1])
    joint_cmd = ((targets - prev_targets) / INCREMENT if self.increments
                 else 2.0 * (targets - lim_lo) / (lim_hi - lim_lo) - 1.0)
    first = np.argmax(self.drive, axis=0)  # (n_action,) each joint dimension's first joint
    parts = [cmd[d] if d in cmd else joint_cmd[first[a]] for a, d in enumerate(self.dims)]
    return jnp.clip(jnp.stack([jnp.asarray(x, jnp.float32) for x in parts]), -1.0, 1.0)

  def belt_speeds(self, v: jax.Array, w: jax.Array) -> jax.Array:
    """(v, w) -> speeds of the 6 belts (m/s): left/right tracks, then the four flippers."""
    return command_belt_speeds(v, w, self.track_separation, self.steering_efficiency, self.max_speed)


def unlock_values(dims: tuple[str, ...], dof_curriculum: tuple[tuple[str, float], ...]) -> np.ndarray:
  """(n_action,) unlock eps per action dimension; ValueError on a name the mode lacks, v / w, or a repeat."""
  unlock = np.zeros(len(dims), np.float32)
  names = [name for name, _ in dof_curriculum]
  for name, eps in dof_curriculum:
    if name not in dims or name in ("v", "w"):
      raise ValueError(f"dof_curriculum: {name!r} is not a joint dimension of {dims}")
    if names.count(name) > 1 or not 0.0 <= eps <= 1.0:
      raise ValueError(f"dof_curriculum: {name!r} must appear once with an eps in [0, 1], got {eps}")
    unlock[dims.index(name)] = eps
  return unlock


def command_belt_speeds(v, w, track_separation: float, steering_efficiency: float,
                        max_speed: float) -> jax.Array:
  """Skid steer: u_side = v - side * w S / (2 e) ... with side +1 left (slower when turning left)."""
  v = jnp.where(jnp.isfinite(v), v, 0.0)
  w = jnp.where(jnp.isfinite(w), w, 0.0)
  diff = w * track_separation / (2.0 * steering_efficiency)
  u = v - jnp.asarray(BELT_SIDE) * diff
  return jnp.clip(u, -max_speed, max_speed)

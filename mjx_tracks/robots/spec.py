"""Typed description of an articulated tracked robot: every dimension, mass and limit."""

from __future__ import annotations

import dataclasses

import numpy as np


FLIPPERS = ("front_left", "front_right", "rear_left", "rear_right")  # flipper order of every robot
ARM_JOINTS = ("arm_1", "arm_2")
# Named groups of position-controlled joints (control dimensions, observation parts, teleop keys).
JOINT_GROUPS: dict[str, tuple[str, ...]] = {
    "flippers": tuple(f"flipper_{f}" for f in FLIPPERS),
    "front": ("flipper_front_left", "flipper_front_right"),
    "rear": ("flipper_rear_left", "flipper_rear_right"),
    **{f: (f"flipper_{f}",) for f in FLIPPERS},
    "arm": ARM_JOINTS,
    **{a: (a,) for a in ARM_JOINTS},
}


@dataclasses.dataclass(frozen=True)
class CapsuleSegment:
  """A collision capsule along a belt's axis, in the belt body's frame."""

  start: float  # m, along the belt axis (x for tracks, along the flipper for flippers)
  end: float  # m
  radius: float  # m


@dataclasses.dataclass(frozen=True)
class FlipperSpec:
  """One flipper: a belt-carrying arm on a hinge at the end of a side track."""

  name: str  # e.g. "front_left"
  pivot: tuple[float, float, float]  # m, in the chassis frame
  direction: float  # +1 points forward (front pair), -1 backward (rear pair)
  side: float  # +1 left, -1 right
  segments: tuple[CapsuleSegment, ...]  # tapered belt as capsules, pivot to tip
  mass: float  # kg


def four_flippers(pivot_x: float, pivot_y: float, segments: tuple[CapsuleSegment, ...],
                  mass: float) -> tuple[FlipperSpec, ...]:
  """Front-left, front-right, rear-left, rear-right flippers on pivots at (+-x, +-y, 0) m."""
  def flipper(name: str) -> FlipperSpec:
    direction = 1.0 if name.startswith("front") else -1.0
    side = 1.0 if name.endswith("left") else -1.0
    return FlipperSpec(name=name, pivot=(pivot_x * direction, pivot_y * side, 0.0),
                       direction=direction, side=side, segments=segments, mass=mass)

  return tuple(flipper(name) for name in FLIPPERS)


@dataclasses.dataclass(frozen=True)
class ArmSpec:
  """A two-joint arm with a fixed link and a payload (robot 1)."""

  base: tuple[float, float, float]  # m, joint 1 position in the chassis frame
  link1_length: float  # m
  link1_mass: float  # kg
  link2_length: float  # m
  link2_mass: float  # kg
  fixed_length: float  # m, fixed link after joint 2
  fixed_mass: float  # kg
  payload_drop: float  # m, payload below the fixed link's end
  payload_mass: float  # kg
  joint1_limit: float  # rad, pitch about the chassis lateral axis
  joint2_limit: float  # rad, about link 1's own axis


@dataclasses.dataclass(frozen=True)
class RobotSpec:
  """Everything that defines a robot model; MJCF and controllers are built from this only."""

  name: str
  chassis_size: tuple[float, float, float]  # m, full box extents (x, y, z)
  chassis_offset_z: float  # m, box centre above the track axis
  chassis_mass: float  # kg, box only
  belly: CapsuleSegment  # skid plate under the chassis, along x, at y = 0
  belly_z: float  # m
  track_y: float  # m, lateral position of each side track's axis
  track: CapsuleSegment  # side track along x
  track_mass: float  # kg, each
  flippers: tuple[FlipperSpec, ...]  # order: front_left, front_right, rear_left, rear_right
  flipper_limit: float  # rad, |angle| limit (0 = flippers in line with the tracks)
  arm: ArmSpec | None
  camera_pos: tuple[float, float, float]  # m, depth camera in the chassis frame
  camera_pitch: float  # rad, pitched down
  camera_hfov: float  # rad, horizontal field of view
  camera_resolution: tuple[int, int]  # px, (width, height)
  camera_range: tuple[float, float]  # m, (near, far)
  imu_pos: tuple[float, float, float]  # m
  lidar_pos: tuple[float, float, float]  # m, the 2D laser scanner (mjx_tracks.envs.scan) in the chassis frame
  # Track-contact (CSM) figures
  mu_along: float  # friction coefficient along the belt
  mu_across: float  # friction coefficient across the belt
  track_separation: float  # m, used by the (v, w) -> belt speed mapping
  steering_efficiency: float  # fraction of the differential belt speed that turns the robot
  max_speed: float  # m/s, belt speed limit
  max_yaw_rate: float  # rad/s, commanded |w| limit
  # Joint servos
  servo_kp: float  # N m / rad
  servo_kv: float  # N m s / rad
  servo_torque: float  # N m, actuator force limit
  joint_armature: float  # kg m^2, reflected rotor inertia

  @property
  def has_arm(self) -> bool:
    return self.arm is not None

  @property
  def spawn_height(self) -> float:
    """Track axis height when resting on flat ground (m)."""
    return self.track.radius

  def pose_lift(self, joint_angles, xp=np):
    """m: how much higher than spawn_height the chassis must start, level, for its flippers at
    joint_angles (rad, joint_names() order) to stay above flat ground. A flipper lowered by phi (a
    negative angle: positive raises the tip) reaches, with each capsule of its belt (end e m from
    the pivot, radius r m), e sin(phi) + r below its pivot, which lies on the track axis; lifted by
    the deepest reach beyond spawn_height (0 where none reaches past it: in line, raised). xp: numpy,
    or jax.numpy where the angles are traced."""
    lowered = xp.maximum(-xp.asarray(joint_angles)[: len(self.flippers)], 0.0)  # (n_flippers,) rad
    reach = [seg.end * xp.sin(lowered[i]) + seg.radius for i, f in enumerate(self.flippers) for seg in f.segments]
    return xp.maximum(xp.max(xp.stack(reach)) - self.spawn_height, 0.0)

  def joint_limits(self) -> np.ndarray:
    """(n_joints, 2) limits of the position-controlled joints: flippers, then arm."""
    lims = [(-self.flipper_limit, self.flipper_limit)] * len(self.flippers)
    if self.arm is not None:
      lims += [(-self.arm.joint1_limit, self.arm.joint1_limit),
               (-self.arm.joint2_limit, self.arm.joint2_limit)]
    return np.array(lims, dtype=np.float32)

  def joint_names(self) -> tuple[str, ...]:
    """Position-controlled joints: flippers in FLIPPERS order, then the arm."""
    names = tuple(f"flipper_{f.name}" for f in self.flippers)
    return names + (ARM_JOINTS if self.arm is not None else ())

  def joint_index(self, group: str) -> np.ndarray:
    """Indices (into joint_names()) of a named joint group; empty where the robot lacks it."""
    if group not in JOINT_GROUPS:
      raise KeyError(f"unknown joint group {group!r}; known: {sorted(JOINT_GROUPS)}")
    names = self.joint_names()
    return np.array([names.index(j) for j in JOINT_GROUPS[group] if j in names], np.int32)

  def joint_vector(self, by_group: dict, xp=np):
    """Joint values (rad, joint_names() order) from angles per joint group (JOINT_GROUPS), 0 for the
    others; xp: numpy, or jax.numpy where the angles are traced."""
    values = xp.zeros(len(self.joint_names()), xp.float32)
    for group, angle in by_group.items():
      index = self.joint_index(group)
      if xp is np:
        values[index] = angle
      else:
        values = values.at[index].set(xp.asarray(angle, xp.float32))
    return values

  def total_mass(self) -> float:
    m = self.chassis_mass + 2 * self.track_mass + sum(f.mass for f in self.flippers)
    if self.arm is not None:
      a = self.arm
      m += a.link1_mass + a.link2_mass + a.fixed_mass + a.payload_mass
    return m

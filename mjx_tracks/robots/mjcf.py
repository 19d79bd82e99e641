"""MJCF for a robot spec: chassis, side tracks, flippers, optional arm, sensor sites."""

from __future__ import annotations

import math

from mjx_tracks.robots.spec import CapsuleSegment, RobotSpec

from scenes.world import ROBOT_CONAFFINITY, ROBOT_CONTYPE, ROBOT_GROUP

CHASSIS_BODY = "chassis"


def _v(*xs: float) -> str:
  return " ".join(f"{x:.6g}" for x in xs)


def _belt_capsule(name: str, seg: CapsuleSegment, axis_sign: float, mass: float,
                  y: float = 0.0, z: float = 0.0) -> str:
  a, b = axis_sign * seg.start, axis_sign * seg.end
  return (f'<geom name="{name}" type="capsule" fromto="{_v(a, y, z, b, y, z)}" '
          f'size="{seg.radius:.6g}" mass="{mass:.6g}" contype="{ROBOT_CONTYPE}" '
          f'conaffinity="{ROBOT_CONAFFINITY}" group="{ROBOT_GROUP}" condim="3" rgba=".15 .15 .15 1"/>')


def _flipper_xml(spec: RobotSpec, i: int) -> str:
  f = spec.flippers[i]
  # hinge about the lateral axis, signed so a positive angle raises the tip
  axis = (0.0, -f.direction, 0.0)
  seg_mass = f.mass / len(f.segments)
  geoms = "\n".join(_belt_capsule(f"belt_flipper_{f.name}_{k}", s, f.direction, seg_mass)
                    for k, s in enumerate(f.segments))
  lo, hi = -spec.flipper_limit, spec.flipper_limit
  return f"""
      <body name="flipper_{f.name}" pos="{_v(*f.pivot)}">
        <joint name="flipper_{f.name}" type="hinge" axis="{_v(*axis)}" range="{lo:.6g} {hi:.6g}"
               limited="true" armature="{spec.joint_armature:.6g}"/>
        {geoms}
      </body>"""


def _arm_xml(spec: RobotSpec) -> str:
  a = spec.arm
  if a is None:
    return ""
  vis = f'contype="0" conaffinity="0" group="{ROBOT_GROUP}"'
  return f"""
      <body name="arm_link1" pos="{_v(*a.base)}">
        <joint name="arm_1" type="hinge" axis="0 1 0" range="{-a.joint1_limit:.6g} {a.joint1_limit:.6g}"
               limited="true" armature="{spec.joint_armature:.6g}"/>
        <geom type="capsule" fromto="0 0 0 0 0 {a.link1_length:.6g}" size="0.025" mass="{a.link1_mass:.6g}" {vis} rgba=".8 .5 .1 1"/>
        <body name="arm_link2" pos="0 0 {a.link1_length:.6g}">
          <joint name="arm_2" type="hinge" axis="0 0 1" range="{-a.joint2_limit:.6g} {a.joint2_limit:.6g}"
                 limited="true" armature="{spec.joint_armature:.6g}"/>
          <geom type="capsule" fromto="0 0 0 0 0 {a.link2_length:.6g}" size="0.02" mass="{a.link2_mass:.6g}" {vis} rgba=".8 .5 .1 1"/>
          <geom type="capsule" fromto="0 0 {a.link2_length:.6g} {a.fixed_length:.6g} 0 {a.link2_length:.6g}" size="0.02" mass="{a.fixed_mass:.6g}" {vis} rgba=".8 .5 .1 1"/>
          <geom name="payload" type="sphere" pos="{_v(a.fixed_length, 0, a.link2_length - a.payload_drop)}" size="0.06" mass="{a.payload_mass:.6g}" {vis} rgba=".2 .4 .8 1"/>
        </body>
      </body>"""


def robot_body_xml(spec: RobotSpec) -> str:
  """The robot's <body> tree, with a free joint, to place in a <worldbody>."""
  cx, cy, cz = (s / 2 for s in spec.chassis_size)
  vis = f'contype="0" conaffinity="0" group="{ROBOT_GROUP}"'
  tracks = "\n".join(
      _belt_capsule(f"belt_track_{side}", spec.track, 1.0, spec.track_mass, y=sgn * spec.track_y)
      for side, sgn in (("left", 1.0), ("right", -1.0)))
  belly = (f'<geom name="belly" type="capsule" fromto="{_v(spec.belly.start, 0, spec.belly_z, spec.belly.end, 0, spec.belly_z)}" '
           f'size="{spec.belly.radius:.6g}" mass="0.001" contype="{ROBOT_CONTYPE}" '
           f'conaffinity="{ROBOT_CONAFFINITY}" group="{ROBOT_GROUP}" condim="3"/>')
  flippers = "".join(_flipper_xml(spec, i) for i in range(len(spec.flippers)))
  cam_quat = _camera_quat(spec.camera_pitch)
  return f"""
    <body name="{CHASSIS_BODY}" pos="0 0 {spec.spawn_height + 0.01:.6g}">
      <freejoint name="root"/>
      <geom name="chassis_box" type="box" pos="0 0 {spec.chassis_offset_z:.6g}" size="{_v(cx, cy, cz)}" mass="{spec.chassis_mass:.6g}" {vis} rgba=".3 .35 .3 1"/>
      {tracks}
      {belly}
      <site name="imu" pos="{_v(*spec.imu_pos)}" size="0.01"/>
      <site name="depth_camera" pos="{_v(*spec.camera_pos)}" quat="{_v(*cam_quat)}" size="0.01"/>
      <camera name="depth_camera" pos="{_v(*spec.camera_pos)}" quat="{_v(*cam_quat)}" fovy="{_vfov_deg(spec):.6g}"/>
      {flippers}
      {_arm_xml(spec)}
    </body>"""


def _camera_quat(pitch_down: float) -> tuple[float, float, float, float]:
  """Quaternion of a camera looking along +x (chassis forward), pitched down by pitch_down rad.

  MuJoCo cameras look along their local -z with +y up; first turn the camera so -z -> +x and
  +y -> +z, then pitch about the chassis y axis.
  """
  # base: rotation taking camera frame (x right, y up, -z forward) to (x -> -y, y -> +z, z -> -x)
  base = (0.5, 0.5, -0.5, -0.5)
  pitch = (math.cos(pitch_down / 2), 0.0, math.sin(pitch_down / 2), 0.0)
  return _qmul(pitch, base)


def _qmul(a, b):
  w1, x1, y1, z1 = a
  w2, x2, y2, z2 = b
  return (w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
          w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
          w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
          w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2)


def _vfov_deg(spec: RobotSpec) -> float:
  w, h = spec.camera_resolution
  return math.degrees(2 * math.atan(math.tan(spec.camera_hfov / 2) * h / w))


def actuators_xml(spec: RobotSpec) -> str:
  """Stiff, damped position servos on every flipper and arm joint."""
  lims = spec.joint_limits()
  lines = []
  for name, (lo, hi) in zip(spec.joint_names(), lims):
    lines.append(
        f'<position name="{name}" joint="{name}" kp="{spec.servo_kp:.6g}" kv="{spec.servo_kv:.6g}" '
        f'ctrlrange="{lo:.6g} {hi:.6g}" ctrllimited="true" '
        f'forcerange="{-spec.servo_torque:.6g} {spec.servo_torque:.6g}" forcelimited="true"/>')
  return "<actuator>\n" + "\n".join(lines) + "\n</actuator>"

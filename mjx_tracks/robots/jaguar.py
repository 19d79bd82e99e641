"""Robot 1: Jaguar V4-like tracked robot with four flippers and a two-joint arm (paper Table I)."""

import math

from mjx_tracks.robots.spec import ArmSpec, CapsuleSegment, RobotSpec, four_flippers

# Flipper belt: roller r = 0.09 m at the pivot tapering to r = 0.035 m at the tip, 0.23 m out (the
# original framework's robot description, Mitriakov et al. 2022). Two capsules follow the taper.
_FLIPPER_SEGMENTS = (
    CapsuleSegment(start=0.0, end=0.11, radius=0.075),
    CapsuleSegment(start=0.11, end=0.23, radius=0.045),
)


JAGUAR = RobotSpec(
    name="jaguar",
    chassis_size=(0.55, 0.37, 0.135),
    chassis_offset_z=0.04,
    chassis_mass=10.14,
    belly=CapsuleSegment(start=-0.21, end=0.21, radius=0.06),
    belly_z=0.02,
    track_y=0.245,
    track=CapsuleSegment(start=-0.23, end=0.23, radius=0.09),
    track_mass=3.03,
    # pivots coaxial with the side tracks' end rollers, outside them: (+-0.23, +-0.315) m
    flippers=four_flippers(0.23, 0.315, _FLIPPER_SEGMENTS, mass=0.5),
    flipper_limit=math.pi / 4,
    arm=ArmSpec(base=(0.0, 0.0, 0.11), link1_length=0.34, link1_mass=1.0,
                link2_length=0.15, link2_mass=0.5, fixed_length=0.15, fixed_mass=0.5,
                payload_drop=0.235, payload_mass=2.0, joint1_limit=1.3, joint2_limit=2.9),
    camera_pos=(0.195, 0.1, 0.295),
    camera_pitch=0.46,
    camera_hfov=1.2,
    camera_resolution=(640, 480),
    camera_range=(0.02, 8.0),
    imu_pos=(0.0, 0.0, 0.0),
    lidar_pos=(-0.15, 0.0, 0.2),  # behind the arm base, 0.09 m above the chassis top
    mu_along=1.0,
    mu_across=0.5,
    track_separation=0.6,
    steering_efficiency=0.5,
    max_speed=1.0,
    max_yaw_rate=1.0,
    servo_kp=600.0,
    servo_kv=40.0,
    servo_torque=150.0,
    joint_armature=0.05,
)

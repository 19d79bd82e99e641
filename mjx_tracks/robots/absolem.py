"""Robot 2: Absolem-like tracked robot, four flippers, no arm (paper Table I: 29 kg, 1.196 x 0.61 x 0.46 m)."""

import math

from mjx_tracks.robots.spec import CapsuleSegment, RobotSpec, four_flippers

# Flipper belt tapering from r = 0.10 m at the pivot to r = 0.04 m at the tip, 0.25 m out.
_FLIPPER_SEGMENTS = (
    CapsuleSegment(start=0.0, end=0.12, radius=0.08),
    CapsuleSegment(start=0.12, end=0.25, radius=0.05),
)


# Length: 2 x 0.25 (pivots) + 2 x (0.25 + 0.05) (flippers) = 1.1 m plus belt thickness ~ 1.196 m;
# width: flippers at +-0.255 m plus belt width 0.05 m = 0.61 m. Mass: 17 + 2 x 4 + 4 x 1 = 29 kg.
ABSOLEM = RobotSpec(
    name="absolem",
    chassis_size=(0.6, 0.32, 0.16),
    chassis_offset_z=0.05,
    chassis_mass=17.0,
    belly=CapsuleSegment(start=-0.22, end=0.22, radius=0.065),
    belly_z=0.03,
    track_y=0.195,
    track=CapsuleSegment(start=-0.25, end=0.25, radius=0.10),
    track_mass=4.0,
    flippers=four_flippers(0.25, 0.255, _FLIPPER_SEGMENTS, mass=1.0),
    flipper_limit=math.pi / 4,
    arm=None,
    camera_pos=(0.25, 0.0, 0.32),
    camera_pitch=0.46,
    camera_hfov=1.2,
    camera_resolution=(640, 480),
    camera_range=(0.02, 8.0),
    imu_pos=(0.0, 0.0, 0.0),
    lidar_pos=(0.0, 0.0, 0.22),  # 0.09 m above the chassis top
    mu_along=1.0,
    mu_across=0.5,
    track_separation=0.5,
    steering_efficiency=0.5,
    max_speed=1.0,
    max_yaw_rate=1.0,
    servo_kp=900.0,
    servo_kv=60.0,
    servo_torque=250.0,
    joint_armature=0.08,
)

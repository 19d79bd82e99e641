"""Physics options and the compiled model of one robot in one world."""

from __future__ import annotations

import dataclasses

import mujoco

from mjx_tracks.bounds import bound, violation
from mjx_tracks.robots.mjcf import actuators_xml, robot_body_xml
from mjx_tracks.robots.spec import RobotSpec


@dataclasses.dataclass(frozen=True)
class PhysicsConfig:
  """MuJoCo options shared by every scene (the `physics` section of a task config; defaults in
  configs/defaults.yaml)."""

  timestep: float = dataclasses.field(metadata=bound(0.0005, 0.02))  # s, one physics substep
  solver_iterations: int = dataclasses.field(metadata=bound(1))  # Newton iterations
  ls_iterations: int = dataclasses.field(metadata=bound(1))  # line-search iterations
  impratio: float = dataclasses.field(metadata=bound(0.0, lo_open=True))  # friction-to-normal impedance ratio
  contact_slots: int  # contacts kept per robot and substep, least distance first (MJX max_contact_points); -1: all
  box_pairs: int  # belt-box pairs tested per substep, nearest bounding spheres first (MJX max_geom_pairs); -1: all

  def validate(self, key: str = "physics") -> None:
    wrong = violation(self)  # the ranges declared on the fields
    if wrong is not None:
      raise ValueError(f"{key}.{wrong[0]}: {wrong[1]}")
    for name in ("contact_slots", "box_pairs"):
      if getattr(self, name) == 0 or getattr(self, name) < -1:
        raise ValueError(f"{key}.{name}: must be -1 (all) or >= 1, got {getattr(self, name)}")


def build_mjcf(robot: RobotSpec, world: str, physics: PhysicsConfig) -> str:
  """Full MJCF text: options, a material (mjx.ray needs one), the world geoms and the robot."""
  return f"""<mujoco model="{robot.name}">
  <compiler angle="radian" autolimits="true"/>
  <option timestep="{physics.timestep}" iterations="{physics.solver_iterations}"
          ls_iterations="{physics.ls_iterations}" solver="Newton" integrator="implicitfast"
          cone="pyramidal" impratio="{physics.impratio}">
    <flag eulerdamp="disable"/>
  </option>
  {_contact_limits_xml(physics)}
  <visual><global offwidth="640" offheight="480"/></visual>
  <asset><material name="world" rgba=".7 .7 .7 1"/></asset>
  <worldbody>
    <light pos="0 0 6" dir="0 0 -1" directional="true"/>
    {world}
    {robot_body_xml(robot)}
  </worldbody>
  {actuators_xml(robot)}
</mujoco>"""


def _contact_limits_xml(physics: PhysicsConfig) -> str:
  """MJX's contact culling (custom numerics; MuJoCo's C engine ignores them and keeps every pair)."""
  limits = {"max_contact_points": physics.contact_slots, "max_geom_pairs": physics.box_pairs}
  numerics = "".join(f'<numeric name="{k}" data="{v}"/>' for k, v in limits.items() if v > 0)
  return f"<custom>{numerics}</custom>" if numerics else ""


def compile_model(robot: RobotSpec, world: str, physics: PhysicsConfig) -> mujoco.MjModel:
  """Compiles the MJCF into a MuJoCo model and checks what the track model's step assumes."""
  physics.validate()
  m = mujoco.MjModel.from_xml_string(build_mjcf(robot, world, physics))
  from mjx_tracks.sim import mjx_private  # noqa: PLC0415  (mujoco.mjx and JAX: not for reading a config)
  mjx_private.check_model(m)
  return m

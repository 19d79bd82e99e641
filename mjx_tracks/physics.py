"""Physics options and the compiled model of one robot in one world."""

from __future__ import annotations

import dataclasses

import mujoco

from mjx_tracks.robots.mjcf import actuators_xml, robot_body_xml
from mjx_tracks.robots.spec import RobotSpec


@dataclasses.dataclass(frozen=True)
class PhysicsConfig:
  """MuJoCo options shared by every scene."""

  timestep: float = 0.01  # s, one physics substep
  solver_iterations: int = 4  # Newton iterations
  ls_iterations: int = 6  # line-search iterations
  impratio: float = 1.0  # friction-to-normal impedance ratio

  def validate(self) -> None:
    if not 0.0005 <= self.timestep <= 0.02:
      raise ValueError(f"physics.timestep must be in [0.0005, 0.02] s, got {self.timestep}")
    if self.solver_iterations < 1 or self.ls_iterations < 1:
      raise ValueError("physics.solver_iterations and physics.ls_iterations must be >= 1")


def build_mjcf(robot: RobotSpec, world: str, physics: PhysicsConfig) -> str:
  """Full MJCF text: options, a material (mjx.ray needs one), the world geoms and the robot."""
  return f"""<mujoco model="{robot.name}">
  <compiler angle="radian" autolimits="true"/>
  <option timestep="{physics.timestep}" iterations="{physics.solver_iterations}"
          ls_iterations="{physics.ls_iterations}" solver="Newton" integrator="implicitfast"
          cone="pyramidal" impratio="{physics.impratio}">
    <flag eulerdamp="disable"/>
  </option>
  <visual><global offwidth="640" offheight="480"/></visual>
  <asset><material name="world" rgba=".7 .7 .7 1"/></asset>
  <worldbody>
    <light pos="0 0 6" dir="0 0 -1" directional="true"/>
    {world}
    {robot_body_xml(robot)}
  </worldbody>
  {actuators_xml(robot)}
</mujoco>"""


def compile_model(robot: RobotSpec, world: str, physics: PhysicsConfig) -> mujoco.MjModel:
  """Compiles the MJCF into a MuJoCo model; every collision geom must use condim 3."""
  physics.validate()
  m = mujoco.MjModel.from_xml_string(build_mjcf(robot, world, physics))
  colliding = (m.geom_contype | m.geom_conaffinity) != 0
  if (m.geom_condim[colliding] != 3).any():
    raise ValueError("the track model expects condim 3 on every colliding geom")
  return m

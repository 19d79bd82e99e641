"""Hand-written flipper / arm controller for straight stairs (the scripted baseline of `drive`)."""

from __future__ import annotations

import dataclasses

import jax.numpy as jnp

from mjx_tracks.robots.spec import RobotSpec


def joint_targets(robot: RobotSpec, by_group: dict[str, jnp.ndarray]) -> jnp.ndarray:
  """Joint target vector (rad, joint_names() order) from angles per joint group; others 0."""
  return robot.joint_vector(by_group, jnp)


@dataclasses.dataclass(frozen=True)
class StairScript:
  """Pitch-driven rules; angles in rad, speeds in m/s."""

  direction: str  # "up" or "down"
  speed: float = 0.4  # m/s on the way up (descent uses 0.75 x)
  climb_pitch: float = 0.1  # rad nose-up (ascent) / nose-down (descent) that means "on the stairs"

  def command(self, robot: RobotSpec, nose_up: jnp.ndarray) -> tuple[float, jnp.ndarray]:
    """(belt speed, joint targets) from the chassis' nose-up angle."""
    return self._up(robot, nose_up) if self.direction == "up" else self._down(robot, nose_up)

  def command_either(self, robot: RobotSpec, nose_up: jnp.ndarray, up: jnp.ndarray) -> tuple[jnp.ndarray, jnp.ndarray]:
    """The up script's command where up (a bool array), else the down script's: the direction as
    data, so that one compiled program drives both ways."""
    (speed_up, targets_up), (speed_down, targets_down) = self._up(robot, nose_up), self._down(robot, nose_up)
    return jnp.where(up, speed_up, speed_down), jnp.where(up, targets_up, targets_down)

  def _up(self, robot: RobotSpec, nose_up: jnp.ndarray) -> tuple[float, jnp.ndarray]:
    lim = robot.flipper_limit
    on_stairs = nose_up >= self.climb_pitch
    # approach: front flippers raised to hook the first edge; climbing: flippers in line,
    # rear pair pushing down a little; arm payload forward to keep the COG ahead.
    return self.speed, joint_targets(robot, {
        "front": jnp.where(on_stairs, 0.0, lim), "rear": jnp.where(on_stairs, -0.3, 0.0),
        "arm_1": 0.8 * jnp.clip(3.0 * nose_up, 0.0, 1.0)})

  def _down(self, robot: RobotSpec, nose_up: jnp.ndarray) -> tuple[float, jnp.ndarray]:
    lim = robot.flipper_limit
    on_stairs = nose_up <= -self.climb_pitch
    # descent: front flippers reach down to the next tread, then all flippers in line; arm
    # payload backward.
    return 0.75 * self.speed, joint_targets(robot, {
        "front": jnp.where(on_stairs, 0.0, -lim), "arm_1": -0.8 * jnp.clip(-3.0 * nose_up, 0.0, 1.0)})

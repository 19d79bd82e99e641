"""Observation parts: a registry of named, documented extractors over one step's sensor readings.

A task's YAML lists the parts it observes (`observation.parts`); one step's observation is their
concatenation in that order. Each part's size comes from `jax.eval_shape` of its extractor, so a
part is defined once, here. With `observation.history` k > 1 the policy sees the last k steps'
observations, newest first (`stack`), so that a feed-forward policy can see how its readings change
(what that did in training: docs/sim-to-real.md, "ONNX").
"""

from __future__ import annotations

import dataclasses
from typing import Callable

import jax
import jax.numpy as jnp
from flax import struct

from mjx_tracks.robots.spec import RobotSpec
from mjx_tracks.sim.layout import BELT_SIDE


@struct.dataclass
class Sensors:
  """Everything an observation part may read, computed once per control step."""

  linear_velocity: jax.Array  # (3,) m/s, chassis frame
  angular_velocity: jax.Array  # (3,) rad/s, chassis frame (roll, pitch, yaw rates)
  rpy: jax.Array  # (3,) rad, roll, pitch (> 0 nose down), yaw
  joints: jax.Array  # (n_joints,) rad, in RobotSpec.joint_names() order
  position: jax.Array  # (3,) m, chassis origin
  goal: jax.Array  # (3,) m
  vertical_beams: jax.Array  # (N_v,) m
  horizontal_beams: jax.Array  # (N_h,) m
  scan: jax.Array  # (rings x N_s,) m, the laser scan (mjx_tracks.envs.scan)
  belts: jax.Array  # (n_belts,) m/s, each belt's speed as its motor's encoder reads it (BELT_SIDE order)

  @staticmethod
  def spec(n_joints: int, n_vertical: int, n_horizontal: int, n_scan: int) -> "Sensors":
    """Shapes only (for jax.eval_shape)."""
    f = lambda *shape: jax.ShapeDtypeStruct(shape, jnp.float32)
    return Sensors(f(3), f(3), f(3), f(n_joints), f(3), f(3), f(n_vertical), f(n_horizontal), f(n_scan),
                   f(len(BELT_SIDE)))


@dataclasses.dataclass(frozen=True)
class ObsPart:
  doc: str
  extract: Callable[[Sensors, RobotSpec], jax.Array]


def _to_goal(s: Sensors) -> jax.Array:
  return s.goal - s.position


def _heading(s: Sensors) -> jax.Array:
  to_goal = _to_goal(s)
  h = jnp.arctan2(to_goal[1], to_goal[0]) - s.rpy[2]
  return jnp.arctan2(jnp.sin(h), jnp.cos(h))[None]


def _joints(group: str):
  return lambda s, robot: s.joints[robot.joint_index(group)]


def _belt_speed(s: Sensors, robot: RobotSpec) -> jax.Array:
  """(2,) m/s, the mean speed of the left and of the right belts: beside the chassis' forward speed
  (part v), how much the tracks slip."""
  left = jnp.asarray(BELT_SIDE) > 0
  return jnp.stack([jnp.mean(s.belts, where=left), jnp.mean(s.belts, where=~left)])


def _flippers_paired(s: Sensors, robot: RobotSpec) -> jax.Array:
  return jnp.stack([s.joints[robot.joint_index("front")].mean(), s.joints[robot.joint_index("rear")].mean()])


PARTS: dict[str, ObsPart] = {
    "v": ObsPart("forward speed (m/s)", lambda s, r: s.linear_velocity[:1]),
    "w": ObsPart("yaw rate (rad/s)", lambda s, r: s.angular_velocity[2:3]),
    "flippers": ObsPart("four flipper angles (rad)", _joints("flippers")),
    "flippers_paired": ObsPart("mean front and mean rear flipper angle (rad)", _flippers_paired),
    "arm": ObsPart("arm joint angles (rad)", _joints("arm")),
    "pitch": ObsPart("chassis pitch (rad, > 0 nose down)", lambda s, r: s.rpy[1:2]),
    "roll": ObsPart("chassis roll (rad)", lambda s, r: s.rpy[0:1]),
    "heading": ObsPart("bearing of the goal relative to the chassis heading (rad)", lambda s, r: _heading(s)),
    "goal_distance": ObsPart("distance to the goal point (m)", lambda s, r: jnp.linalg.norm(_to_goal(s))[None]),
    "angular_velocity": ObsPart("chassis angular velocity (rad/s)", lambda s, r: s.angular_velocity),
    "vertical_beams": ObsPart("vertical depth beams (m)", lambda s, r: s.vertical_beams),
    "horizontal_beams": ObsPart("horizontal depth beams (m)", lambda s, r: s.horizontal_beams),
    "belt_speed": ObsPart("mean left and mean right belt speed, as the belt motors' encoders read them (m/s)",
                          _belt_speed),
    "scan": ObsPart("laser scan around the chassis, ray j N_s + k at yaw 2 pi k / N_s in ring j (m)", lambda s, r: s.scan),
}


def part_sizes(parts: tuple[str, ...], robot: RobotSpec, n_vertical: int, n_horizontal: int,
               n_scan: int) -> dict[str, int]:
  """Size of each listed part, from the shape of its extractor's output."""
  spec = Sensors.spec(len(robot.joint_names()), n_vertical, n_horizontal, n_scan)
  return {p: jax.eval_shape(lambda s, p=p: PARTS[p].extract(s, robot), spec).shape[0] for p in parts}


def observe(parts: tuple[str, ...], s: Sensors, robot: RobotSpec) -> jax.Array:
  """The observation vector: the listed parts concatenated, non-finite entries as 0."""
  obs = jnp.concatenate([PARTS[p].extract(s, robot) for p in parts])
  return jnp.nan_to_num(obs, nan=0.0, posinf=0.0, neginf=0.0)


def stack(current: jax.Array, previous: jax.Array | None, history: int) -> jax.Array:
  """The observation of k = history steps, newest first: the current step's parts (n,), then the
  first (k - 1) n entries of the previous stacked observation ((k n,): its k - 1 newest steps);
  previous None (an episode's first step): k copies of the current one."""
  if previous is None:
    return jnp.tile(current, history)
  return jnp.concatenate([current, previous[: (history - 1) * current.shape[0]]])


def observation_entries(parts: tuple[str, ...], sizes: dict[str, int], history: int = 1) -> list[tuple[str, str, int]]:
  """(name, part, control steps back) per observation entry, in order; an older step's entries are
  named NAME@t-j (j steps back)."""
  one = [(p if sizes[p] == 1 else f"{p}[{i}]", p) for p in parts for i in range(sizes[p])]
  return [(f"{n}@t-{j}" if j else n, p, j) for j in range(history) for n, p in one]


def observation_names(parts: tuple[str, ...], sizes: dict[str, int], history: int = 1) -> list[str]:
  """One name per observation entry, in order (observation_entries)."""
  return [name for name, _, _ in observation_entries(parts, sizes, history)]

"""Baselines: policies that a trained one must beat, evaluated like trained policies (`python -m
train.evaluate --baseline NAME --task TASK`) and shown beside them in study reports and the
dashboard. Each acts on a batch of env states (a scripted controller may read the whole state):

  zero      every action 0: half the speed range (0.5 m/s on the stairs), joints held
  full      full speed, joints held
  random    every action ~ U(-1, 1) per dimension and step (from the env state's own key)
  scripted  the stair script (mjx_tracks.tools.scripted): pitch-driven flipper and arm rules at a
            moderate speed; stair tasks whose control mode drives the front flippers

A task whose best constant baseline (CONSTANT) succeeds in at least SATURATED of the trials on its
hardest scene is saturated: success there says nothing about learning.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING, Callable

# JAX is imported where a baseline acts, so that study specs and the dashboard that name baselines
# start without it
if TYPE_CHECKING:
  from mjx_tracks.envs.config import TaskConfig
  from mjx_tracks.envs.task_env import TrackedRobotEnv

ALGO = "baseline"  # a baseline's "algorithm" in its run record and the database
CONSTANT = ("zero", "full")  # the constant-action baselines (saturation is judged on them)
SATURATED = 0.9  # success on the hardest scene at or above which a constant baseline saturates a task
RANDOM_STREAM = 7  # fold_in of the env state's key that the random baseline draws from


@dataclasses.dataclass(frozen=True)
class Baseline:
  name: str
  meaning: str
  applies: Callable[["TaskConfig"], bool]  # whether it can drive the task
  make: Callable[["TrackedRobotEnv"], Callable]  # core -> act(states) -> actions (batch)


def constant_act(core, action):
  """act(states) -> the same action vector for every state of the batch."""
  import jax.numpy as jnp  # noqa: PLC0415
  return lambda states: jnp.broadcast_to(action, (states.obs.shape[0], core.action_size))


def _constant(speed: float):
  def make(core):
    import jax.numpy as jnp  # noqa: PLC0415
    return constant_act(core, jnp.zeros(core.action_size).at[0].set(speed))  # action 0 is v in every control mode
  return make


def _random(core):
  import jax  # noqa: PLC0415

  def one(key):
    return jax.random.uniform(jax.random.fold_in(key, RANDOM_STREAM), (core.action_size,), minval=-1.0, maxval=1.0)
  return lambda states: jax.vmap(one)(states.pipeline_state.key)


def _scripted(core):
  import jax  # noqa: PLC0415
  import jax.numpy as jnp  # noqa: PLC0415

  from mjx_tracks.sim.pose import chassis_rpy  # noqa: PLC0415
  from mjx_tracks.tools.scripted import StairScript  # noqa: PLC0415
  script, robot, c = StairScript(core.cfg.scene.direction), core.robot, core.controller

  def one(es):
    speed, targets = script.command(robot, -chassis_rpy(es.data.qpos)[1])
    return c.encode(jnp.float32(speed), jnp.float32(0.0), jnp.clip(targets, c.joint_limits[:, 0], c.joint_limits[:, 1]),
                    es.targets)
  return lambda states: jax.vmap(one)(states.pipeline_state)


def _scriptable(cfg) -> bool:
  """Whether the task's scene kind has the stair script and its control mode drives the front flippers."""
  from mjx_tracks.sim.control import CONTROL_MODES  # noqa: PLC0415
  from scenes.kinds import scene_kind  # noqa: PLC0415
  return scene_kind(cfg.scene.kind).stair_script and "front" in CONTROL_MODES[cfg.control.mode]


BASELINES: dict[str, Baseline] = {b.name: b for b in (
    Baseline("zero", "every action 0 (half speed, joints held)", lambda cfg: True, _constant(0.0)),
    Baseline("full", "full speed, joints held", lambda cfg: True, _constant(1.0)),
    Baseline("random", "actions ~ U(-1, 1) each step", lambda cfg: True, _random),
    Baseline("scripted", "the stair script: pitch-driven flipper and arm rules", _scriptable, _scripted),
)}


def baseline(name: str) -> Baseline:
  """The baseline of that name (ValueError naming the known ones)."""
  if name not in BASELINES:
    raise ValueError(f"unknown baseline {name!r}; known: {', '.join(BASELINES)}")
  return BASELINES[name]


def baselines_for(cfg: "TaskConfig", names=tuple(BASELINES)) -> list[str]:
  """The named baselines that can drive the task, in registry order."""
  return [n for n in BASELINES if n in names and BASELINES[n].applies(cfg)]


def saturated(success_by_baseline: dict[str, float]) -> bool:
  """Whether a constant baseline's success on the hardest scene reaches SATURATED."""
  return any(success_by_baseline.get(n, 0.0) >= SATURATED for n in CONSTANT)

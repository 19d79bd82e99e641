"""A process traces each model's physics substep once: `step_with_tracks` is jitted at module level
with its track model hashed by value, so a second simulator of the same robot, world and physics
(another env, another program of the same task) reuses the first one's trace; other physics
trace anew."""

import dataclasses

import jax
import jax.numpy as jnp

from mjx_tracks.robots import get_robot
from mjx_tracks.sim import mjx_private
from mjx_tracks.sim.simulator import staircase_simulator


def _trace_substep(sim) -> None:
  """Traces (nothing compiled) one substep of the simulator's model, as a program's tracing would."""
  d = sim.init_data(jnp.zeros(3), jnp.float32(0.0))
  jax.eval_shape(lambda d: sim.substep(sim.model, d, jnp.zeros(4)), d)


def test_a_second_simulator_of_the_same_physics_reuses_the_trace_and_other_physics_do_not(monkeypatch,
                                                                                          default_physics):
  traced = []  # mjx_private.step runs once per trace of the substep, never on a cache hit
  real = mjx_private.step
  monkeypatch.setattr(mjx_private, "step", lambda *a: traced.append(1) or real(*a))
  first, again = staircase_simulator(get_robot(1), default_physics), staircase_simulator(get_robot(1), default_physics)
  assert first is not again and first.tracks == again.tracks and hash(first.tracks) == hash(again.tracks)
  _trace_substep(first)
  before = len(traced)  # 1, or 0 where an earlier test of this process traced it
  _trace_substep(again)
  assert len(traced) == before
  other = staircase_simulator(get_robot(1), dataclasses.replace(default_physics, solver_iterations=7))
  _trace_substep(other)  # MJX keeps the solver's iterations in the model's static fields
  assert len(traced) == before + 1

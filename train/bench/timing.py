"""Timing of compiled functions: the first call (compilation) apart from the steady state."""

from __future__ import annotations

import time

import jax


def timed(fn, state, make_args, reps: int) -> tuple[float, float]:
  """(compile s, s per call) of state = fn(state, *make_args(i)), the first call timed alone."""
  t = time.time()
  state = jax.block_until_ready(fn(state, *make_args(0)))
  compile_s = time.time() - t
  t = time.time()
  for i in range(reps):
    state = fn(state, *make_args(i + 1))
  jax.block_until_ready(state)
  return compile_s, (time.time() - t) / reps


def time_env_step(core, n: int, reps: int):
  """(first state, compile s, s per batched step) of the task's batched env, n robots, random actions."""
  from mjx_tracks.envs.wrappers import batched_env  # noqa: PLC0415
  env = batched_env(core)
  state = jax.jit(env.reset)(jax.random.split(jax.random.PRNGKey(0), n))
  actions = lambda i: (jax.random.uniform(jax.random.PRNGKey(i), (n, core.action_size), minval=-1, maxval=1),)  # noqa: E731
  compile_s, step_s = timed(jax.jit(env.step), state, actions, reps)
  return state, compile_s, step_s

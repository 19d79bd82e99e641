"""Timing of compiled functions: the first call (compilation) apart from the steady state."""

from __future__ import annotations

import os
import subprocess
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


def process_wall_s(cmd: list[str], cache: str | None, log: str | None = None) -> tuple[int, float]:
  """(exit code, wall s from start to exit) of a process; cache: a compilation cache folder of its
  own (MJX_TRACKS_CACHE; an empty one compiles from scratch), None: the machine's; log: where its
  output goes (default: this process's)."""
  env = dict(os.environ) if cache is None else {**os.environ, "MJX_TRACKS_CACHE": cache}
  t0 = time.time()
  if log is None:
    rc = subprocess.call(cmd, env=env)
  else:
    with open(log, "w") as f:
      rc = subprocess.call(cmd, stdout=f, stderr=subprocess.STDOUT, env=env)
  return rc, time.time() - t0

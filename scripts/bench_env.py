"""Full environment throughput (physics substeps + track model + beams + monitor + curriculum
resets) at several batch sizes, next to the simulator's bare physics step of the same scenes.

python scripts/bench_env.py [--task asc-inc-cog] [--envs 1024,4096,16384] [--reps 5] [--out FILE]
"""

from __future__ import annotations

import argparse
import json
import sys
import time

import jax
import jax.numpy as jnp

import mjx_tracks
from mjx_tracks.envs.wrappers import batched_env
from result_file import write_result


def timed(fn, state, make_args, reps):
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
  env = batched_env(core)
  state = jax.jit(env.reset)(jax.random.split(jax.random.PRNGKey(0), n))
  actions = lambda i: (jax.random.uniform(jax.random.PRNGKey(i), (n, core.action_size), minval=-1, maxval=1),)
  compile_s, step_s = timed(jax.jit(env.step), state, actions, reps)
  return state, compile_s, step_s


def main(argv=None) -> int:
  p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  p.add_argument("--task", default="asc-inc-cog")
  p.add_argument("--envs", default="1024,4096,16384")
  p.add_argument("--reps", type=int, default=5)
  p.add_argument("--out")
  args = p.parse_args(argv)
  core = mjx_tracks.load(args.task)
  sim, k = core.sim, core.substeps
  rows = []
  for n in [int(x) for x in args.envs.split(",")]:
    state, env_compile, env_s = time_env_step(core, n, args.reps)

    def bare(es, belts, targets):  # the simulator alone on the same scenes
      m = sim.with_boxes(es.scene.box_pos, es.scene.box_size, es.scene.box_yaw)
      return es.replace(data=sim.advance(m, es.data, belts, targets, k))

    belts = jnp.full((n, 6), 0.5)
    targets = jnp.zeros((n, sim.layout.n_joints))
    sim_compile, sim_s = timed(jax.jit(jax.vmap(bare)), state.pipeline_state, lambda i: (belts, targets), args.reps)
    row = {"envs": n, "substeps_per_control_step": k,
           "env_control_steps_per_s": round(n / env_s), "env_substeps_per_s": round(n * k / env_s),
           "bare_control_steps_per_s": round(n / sim_s), "env_fraction_of_bare": round(sim_s / env_s, 3),
           "env_compile_s": round(env_compile, 2), "bare_compile_s": round(sim_compile, 2)}
    rows.append(row)
    print(json.dumps(row), flush=True)
  write_result(args.out, rows, task=args.task)
  return 0


if __name__ == "__main__":
  sys.exit(main())

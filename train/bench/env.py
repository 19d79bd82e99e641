"""env: full environment throughput (physics substeps + track model + beams + monitor + curriculum
resets) at several batch sizes, next to the simulator's bare physics step of the same scenes."""

from __future__ import annotations

import json

from train.bench.timing import time_env_step, timed


def add_args(p) -> None:
  p.add_argument("--task", default="asc-inc-cog")
  p.add_argument("--envs", default="1024,4096,16384", help="robot counts, comma-separated")
  p.add_argument("--reps", type=int, default=5)
  p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="config override")


def run(args) -> tuple[list[dict], dict]:
  import jax  # noqa: PLC0415
  import jax.numpy as jnp  # noqa: PLC0415

  import mjx_tracks  # noqa: PLC0415
  core = mjx_tracks.load(args.task, args.set)
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
    rows.append({"envs": n, "substeps_per_control_step": k,
                 "env_control_steps_per_s": round(n / env_s), "env_substeps_per_s": round(n * k / env_s),
                 "bare_control_steps_per_s": round(n / sim_s), "env_fraction_of_bare": round(sim_s / env_s, 3),
                 "env_compile_s": round(env_compile, 2), "bare_compile_s": round(sim_compile, 2)})
    print(json.dumps(rows[-1]), flush=True)
  return rows, {"task": args.task, "overrides": list(args.set)}

"""physics: simulator throughput, physics substeps/s and control steps/s of batched robots on
staircases, with the track model and with plain mjx.step of the same model, plus compile times.

Each environment gets its own random 7-step-pool staircase (l ~ U(0.35, 0.52) m, h ~ U(0.12, 0.22) m,
n ~ U{1..7}) and drives toward it at 0.5 m/s with random flipper targets ~ U(-0.5, 0.5) rad."""

from __future__ import annotations

import json

from train.bench.timing import timed


def add_args(p) -> None:
  p.add_argument("--envs", default="1024,4096,16384", help="robot counts, comma-separated")
  p.add_argument("--substeps", type=int, default=25, help="physics substeps per control step")
  p.add_argument("--reps", type=int, default=5)
  p.add_argument("--robot", default="1")


def batch_state(sim, n_envs: int, key):
  """Per-env scene boxes and data: random staircases, robots at the ascent spawn + 0.5 m."""
  import jax  # noqa: PLC0415
  import jax.numpy as jnp  # noqa: PLC0415

  from scenes import staircase as sc  # noqa: PLC0415
  k1, k2, k3 = jax.random.split(key, 3)
  stairs = sc.Staircase(jax.random.uniform(k1, (n_envs,), minval=0.35, maxval=0.52),
                        jax.random.uniform(k2, (n_envs,), minval=0.12, maxval=0.22),
                        jax.random.randint(k3, (n_envs,), 1, 8))

  def one(st):
    pos, yaw = sc.ascent_spawn(st)
    d = sim.init_data(pos + jnp.array([0.5, 0.0, 0.0]), yaw, jnp.zeros(sim.layout.n_joints))
    return sc.step_boxes(st), d

  return jax.jit(jax.vmap(one))(stairs)


def run(args) -> tuple[list[dict], dict]:
  import jax  # noqa: PLC0415
  import jax.numpy as jnp  # noqa: PLC0415

  from mjx_tracks.envs.config import default_config  # noqa: PLC0415
  from mjx_tracks.robots import get_robot  # noqa: PLC0415
  from mjx_tracks.sim.simulator import staircase_simulator  # noqa: PLC0415
  sim, k = staircase_simulator(get_robot(args.robot), default_config().physics), args.substeps

  def tracks(boxes, belts, targets, d):
    return sim.advance(sim.with_boxes(*boxes), d, belts, targets, k)

  def plain(boxes, belts, targets, d):
    m = sim.with_boxes(*boxes)
    d = d.replace(ctrl=targets)
    return jax.lax.fori_loop(0, k, lambda _, x: sim.plain_step(m, x), d)

  rows = []
  for n in [int(x) for x in args.envs.split(",")]:
    m, d = batch_state(sim, n, jax.random.PRNGKey(n))
    belts = jnp.full((n, 6), 0.5)
    targets = jax.random.uniform(jax.random.PRNGKey(1), (n, sim.layout.n_joints), minval=-0.5, maxval=0.5)
    row = {"envs": n, "substeps_per_control_step": k}
    for name, fn in (("tracks", tracks), ("plain_mjx_step", plain)):
      vf = jax.jit(jax.vmap(fn))
      compile_s, per_call = timed(lambda data, vf=vf: vf(m, belts, targets, data), d, lambda i: (), args.reps)
      row.update({f"{name}_compile_s": round(compile_s, 2), f"{name}_substeps_per_s": round(n * k / per_call),
                  f"{name}_control_steps_per_s": round(n / per_call)})
    row["track_model_overhead"] = round(row["plain_mjx_step_substeps_per_s"] / row["tracks_substeps_per_s"] - 1, 3)
    rows.append(row)
    print(json.dumps(row), flush=True)
  return rows, {"robot": sim.robot.name}

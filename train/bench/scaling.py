"""scaling: bare mjx.step of the task's model, the environment step, + policy inference, + PPO
training, at several robot counts on one device, with simulated seconds per wall second.

"bare" steps the same model and scenes (with contact culling) through plain mjx.step, without the
track model, sensors, rewards or resets; "inference" adds the GPU preset's PPO policy (3 x 128,
observation normalizer, sampled actions); "training" is whole PPO updates of the GPU preset
(rollout + 4 epochs of SGD) at that many robots, in environment steps per second."""

from __future__ import annotations

import json
import sys
import tempfile
import time

from train.bench.timing import time_env_step, timed


def add_args(p) -> None:
  p.add_argument("--task", default="asc-inc-cog")
  p.add_argument("--envs", default="1024,4096,16384,32768", help="robot counts, comma-separated")
  p.add_argument("--reps", type=int, default=5)
  p.add_argument("--updates", type=int, default=3, help="timed PPO updates per size (0: no training row)")


def bare_step_s(core, state, reps: int) -> float:
  """Seconds per control step of plain mjx.step substeps on the env's scenes and robot states."""
  import jax  # noqa: PLC0415
  sim, k = core.sim, core.substeps

  def bare(es):
    m = sim.with_boxes(es.scene.box_pos, es.scene.box_size, es.scene.box_yaw)
    return es.replace(data=jax.lax.fori_loop(0, k, lambda _, x: sim.plain_step(m, x), es.data))

  return timed(jax.jit(jax.vmap(bare)), state.pipeline_state, lambda i: (), reps)[1]


def inference_step_s(core, state, reps: int) -> float:
  """Seconds per control step of the env driven by the GPU preset's PPO policy (sampled actions)."""
  import jax  # noqa: PLC0415

  from mjx_tracks.envs.wrappers import batched_env  # noqa: PLC0415
  from train.core.networks import NetworkSpec  # noqa: PLC0415
  from train.core.policy import act_from_params  # noqa: PLC0415
  from train.core.presets import get_preset  # noqa: PLC0415
  p = get_preset("ppo", "gpu")
  spec = NetworkSpec("ppo", core.observation_size, core.action_size, p.policy_hidden, p.value_hidden)
  act = act_from_params(spec, deterministic=False)(spec.init_policy_params())
  env = batched_env(core)
  return timed(jax.jit(lambda s: env.step(s, act(s.obs))), state, lambda i: (), reps)[1]


def training_steps_per_s(task: str, n: int, updates: int) -> tuple[float, float]:
  """(environment steps/s of whole PPO updates of the GPU preset at n robots, compile s)."""
  import jax  # noqa: PLC0415

  from train.core.build import build, compile_update, init_state  # noqa: PLC0415
  from train.core.plan import plan_run  # noqa: PLC0415
  from train.run import parser  # noqa: PLC0415
  out = tempfile.mkdtemp(prefix="bench-scaling-")
  plan = plan_run(parser().parse_args(["--task", task, "--preset", "gpu", "--num-envs", str(n),
                                       "--probe-every", "0", "--out", out]))
  t = build(plan)
  update, compile_s = compile_update(t, stream=sys.stderr)
  state, _ = update(init_state(t, 0))
  jax.block_until_ready(state)
  t0 = time.time()
  for _ in range(updates):
    state, _ = update(state)
  jax.block_until_ready(state)
  return t.learner.steps_per_update * updates / (time.time() - t0), compile_s


def row_for(task: str, n: int, reps: int, updates: int) -> dict:
  import mjx_tracks  # noqa: PLC0415
  core = mjx_tracks.load(task)
  state, env_compile, env_s = time_env_step(core, n, reps)
  period = core.cfg.control.period  # s of simulated time per control step
  rates = {"bare_mjx_step": n / bare_step_s(core, state, reps), "env_step": n / env_s,
           "env_plus_inference": n / inference_step_s(core, state, reps)}
  rates["env_plus_training"], train_compile = training_steps_per_s(task, n, updates) if updates else (None, None)
  row = {"envs": n, "control_period_s": period, "env_compile_s": round(env_compile, 1),
         "training_compile_s": None if train_compile is None else round(train_compile, 1)}
  for name, r in rates.items():
    row[f"{name}_steps_per_s"] = None if r is None else round(r)
    row[f"{name}_sim_s_per_s"] = None if r is None else round(r * period)
  return row


def run(args) -> tuple[list[dict], dict]:
  rows = []
  for n in [int(x) for x in args.envs.split(",")]:
    rows.append(row_for(args.task, n, args.reps, args.updates))
    print(json.dumps(rows[-1]), flush=True)
  return rows, {"task": args.task}

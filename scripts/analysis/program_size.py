"""How large the programs inside the PPO training step are, by part (issue 30, compile time):
StableHLO operations and text size of a task's environment step (one robot), its physics substeps
(`TrackedRobotEnv._advance`), its sensors, the auto-reset's `reset_at`, the batched step with
the auto-reset (8 robots) and the whole PPO training step (`gpu` preset), each lowered with
`jax.jit(...).lower` (tracing and lowering only, nothing compiled). CPU, under a minute.
With --compile, then XLA's compilation time of the whole PPO training step and of two of its parts
at its 4,096 robots (the batched step with the auto-reset; the physics substep loop alone), each
from no cache (~1 min more on a CPU): how much of the step's compilation a part compiled apart, in
parallel with the others, would leave (issue 30's 20 s target).

    python scripts/analysis/program_size.py [--task asc-inc-cog] [--set KEY=VALUE ...] [--compile]
"""

from __future__ import annotations

import argparse
import collections
import re
import sys
import time

import jax
import jax.numpy as jnp

from mjx_tracks.envs.config import ConfigError, load_config
from mjx_tracks.envs.task_env import TrackedRobotEnv
from mjx_tracks.envs.wrappers import batched_env
from mjx_tracks.sim.layout import BELT_SIDE


def size(name: str, f, *args) -> None:
  """Prints the lowered program's operation count (its while loops and calls) and lowering time."""
  t0 = time.time()
  text = jax.jit(f).lower(*args).as_text()
  ops = collections.Counter(re.findall(r"= \"?(stablehlo\.[a-z_]+|func\.call)", text))
  print(f"{name}: {sum(ops.values()):,} operations (while {ops['stablehlo.while']}, calls {ops['func.call']}), "
        f"{len(text) / 1e6:.2f} MB of text, traced and lowered in {time.time() - t0:.1f} s", flush=True)


def main() -> None:
  p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  p.add_argument("--task", default="asc-inc-cog")
  p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a config setting, repeatable")
  p.add_argument("--compile", action="store_true", help="also time XLA's compilation of the step and its parts")
  args = p.parse_args()
  if args.compile:
    jax.config.update("jax_enable_compilation_cache", False)  # every program compiled from nothing
  try:
    env = TrackedRobotEnv(load_config(args.task, tuple(args.set)))
  except ConfigError as e:
    sys.exit(f"error: {e}")
  key = jax.random.PRNGKey(0)
  state = env.reset(key)
  es = state.pipeline_state
  model = env._model(es.scene, es.robust)  # noqa: SLF001 (the step's own model of this scene)
  size("env step (1 robot)", env.step, state, jnp.zeros(env.action_size))
  belts = jnp.zeros(len(BELT_SIDE))  # m/s, one speed per belt, as the controller commands
  size("  physics substeps", lambda s, b, t: env._advance(model, s, b, t), es, belts, es.targets)  # noqa: SLF001
  size("  sensors", lambda s, k: env.sensors(s, model, k), es, key)
  size("reset_at (1 robot)", env.reset_at, key, jnp.float32(0.5), jnp.float32(1.0))
  batched = batched_env(env)
  size("batched step with auto-reset (8 robots)", batched.step, batched.reset(jax.random.split(key, 8)),
       jnp.zeros((8, env.action_size)))
  size_update(args.task, args.set, args.compile)


def compiled(name: str, f, *args) -> None:
  """Prints how long XLA takes to compile f's program (its tracing and lowering apart)."""
  t0 = time.time()
  lowered = jax.jit(f).lower(*args)
  t1 = time.time()
  lowered.compile()
  print(f"{name}: traced and lowered in {t1 - t0:.1f} s, XLA compiled it in {time.time() - t1:.1f} s", flush=True)


def compile_parts(env: TrackedRobotEnv, n: int) -> None:
  """XLA's time for two parts of the PPO step at n robots: the batched step with its auto-reset,
  and the physics substeps alone (TrackedRobotEnv._advance of each robot's own scene model)."""
  batched = batched_env(env)
  states = jax.eval_shape(batched.reset, jax.random.split(jax.random.PRNGKey(0), n))
  compiled(f"  batched step with auto-reset ({n:,} robots)", batched.step, states,
           jax.ShapeDtypeStruct((n, env.action_size), jnp.float32))

  def physics(es, belts):
    def one(es, b):
      return env._advance(env._model(es.scene, es.robust), es, b, es.targets)[0]  # noqa: SLF001
    return jax.vmap(one)(es, belts)
  compiled(f"  physics substeps alone ({n:,} robots)", physics, states.pipeline_state,
           jax.ShapeDtypeStruct((n, len(BELT_SIDE)), jnp.float32))


def size_update(task: str, settings: list[str], compile_it: bool = False) -> None:
  """The whole PPO training step of `train.run --task TASK --preset gpu --set ...` (4,096 robots:
  rollout, SGD epochs), lowered for the state's shapes: what "compiled in N s" compiles; compiled
  too where compile_it."""
  from train import run  # noqa: PLC0415
  from train.core.build import build, shaped_state  # noqa: PLC0415
  from train.core.plan import plan_run  # noqa: PLC0415
  argv = ["--task", task, "--preset", "gpu", *(a for s in settings for a in ("--set", s))]
  t = build(plan_run(run.parser().parse_args(argv)))  # its run folder is named, never made
  size("PPO training step (gpu preset, 4,096 robots)", t.learner.update, shaped_state(t))
  if compile_it:
    compiled("PPO training step (gpu preset, 4,096 robots)", t.learner.update, shaped_state(t))
    compile_parts(t.core, t.plan.num_envs)  # the run's own environment (its preset's settings)


if __name__ == "__main__":
  main()

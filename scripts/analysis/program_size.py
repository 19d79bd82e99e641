"""How large the programs inside the PPO training step are, by part (issue 30, compile time):
StableHLO operations and text size of a task's environment step (one robot), its physics substeps
(`TrackedRobotEnv._advance`), its sensors, the auto-reset's `reset_at`, the batched step with
the auto-reset (8 robots) and the whole PPO training step (`gpu` preset), each lowered with
`jax.jit(...).lower` (tracing and lowering only, nothing compiled). CPU, under a minute.

    python scripts/analysis/program_size.py [--task asc-inc-cog] [--set KEY=VALUE ...]
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
  args = p.parse_args()
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
  size_update(args.task, args.set)


def size_update(task: str, settings: list[str]) -> None:
  """The whole PPO training step of `train.run --task TASK --preset gpu --set ...` (4,096 robots:
  rollout, SGD epochs), lowered for the state's shapes: what "compiled in N s" compiles."""
  from train import run  # noqa: PLC0415
  from train.core.build import build, shaped_state  # noqa: PLC0415
  from train.core.plan import plan_run  # noqa: PLC0415
  argv = ["--task", task, "--preset", "gpu", *(a for s in settings for a in ("--set", s))]
  t = build(plan_run(run.parser().parse_args(argv)))  # its run folder is named, never made
  size("PPO training step (gpu preset, 4,096 robots)", t.learner.update, shaped_state(t))


if __name__ == "__main__":
  main()

"""gym: the Gymnasium path as a library's training loop drives it: `TrackedRobotGymEnv` (one robot,
numpy in and out, a Python call per control step) and `TrackedRobotVectorEnv` at several robot
counts, random actions, resets included; control steps per second after the first (compiling) call,
and the compile time (from the persistent cache when it holds the programs)."""

from __future__ import annotations

import json
import time

import numpy as np


def add_args(p) -> None:
  p.add_argument("--task", default="asc-inc-cog")
  p.add_argument("--envs", default="1,64", help="robot counts of the VectorEnv, comma-separated (1: the single Env)")
  p.add_argument("--steps", type=int, default=500, help="control steps timed per robot count")
  p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="config override")


def _rate(env, steps: int, sample) -> tuple[float, float]:
  """(compile s, control steps per s of all robots) of env.step with random actions."""
  t0 = time.perf_counter()
  env.reset(seed=0)
  env.step(sample())
  compile_s = time.perf_counter() - t0
  t0 = time.perf_counter()
  for _ in range(steps):
    env.step(sample())
  return compile_s, steps / (time.perf_counter() - t0)


def run(args) -> tuple[list[dict], dict]:
  from mjx_tracks.envs.gym_env import TrackedRobotGymEnv, TrackedRobotVectorEnv  # noqa: PLC0415
  rng = np.random.default_rng(0)
  rows = []
  for n in [int(x) for x in args.envs.split(",")]:
    t0 = time.perf_counter()
    env = TrackedRobotGymEnv(args.task, args.set) if n == 1 else TrackedRobotVectorEnv(args.task, n, args.set)
    build_s = time.perf_counter() - t0  # compiles reset and step (gym_env._Stack)
    shape = env.action_space.shape
    compile_s, rate = _rate(env, args.steps, lambda: rng.uniform(-1, 1, shape).astype(np.float32))
    rows.append({"env": "Env" if n == 1 else "VectorEnv", "robots": n, "build_and_compile_s": round(build_s + compile_s, 2),
                 "control_steps_per_s": round(rate * n, 1), "calls_per_s": round(rate, 1)})
    print(json.dumps(rows[-1]), flush=True)
  return rows, {"task": args.task, "overrides": list(args.set), "steps": args.steps}

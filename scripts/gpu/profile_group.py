"""Issue 30, where a program's control step goes: for n runs in one program (`train.run --seeds`), the
training step's seconds per control step, the same for the environments' steps alone (zero actions,
no learning: the physics and the env's bookkeeping), and a profile of one training step on the
device: how many kernels it launches per control step, how long the device is busy against the
wall time, how many device-to-host copies (each while-loop iteration's predicate on a GPU), and
the kernels that take the most time; and the same for the program's Brax evaluation. Writes
OUT/profile-group.json with the device, command and date.

Usage (GPU host): python scripts/gpu/profile_group.py OUT [--runs 1,20,40] [--updates 4] -- TRAIN.RUN ARGS
E.g. the paper study's SAC program: -- --tasks asc-inc-cog,asc-uni-cog,des-inc-ang,des-uni-ang --algo sac
--preset paper --hp max_replay_size=20000 (--runs n takes seeds 0..n/4-1 of each task: n a multiple of 4;
without --tasks, seeds 0..n-1 of --task)."""

from __future__ import annotations

import argparse
import collections
import datetime
import gzip
import json
import os
import pathlib
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402

from train.core.group import build_group, group_evaluations, group_tasks, init_group, lower_group  # noqa: E402
from train.core.build import learner_on  # noqa: E402
from train.run import group_plans, parser, plan_run  # noqa: E402


def plans_of(argv: list[str], n: int):
  """The plans of n runs of `train.run ARGV` in one program (seeds spread over --tasks)."""
  args = parser().parse_args(argv)
  tasks = args.tasks.split(",") if args.tasks else [args.task]
  if n % len(tasks):
    raise SystemExit(f"error: --runs {n} is not a multiple of the {len(tasks)} tasks")
  per = n // len(tasks)
  if n == 1:
    return [plan_run(argparse.Namespace(**{**vars(args), "seed": 0, "out": None}))]
  args.seeds = ",".join(str(s) for s in range(per))
  return group_plans(args)


def seconds_per_call(f, x, calls: int):
  """(output, seconds per call) of `calls` calls of f chained on x, after one call outside the clock."""
  x = jax.block_until_ready(f(x))
  t0 = time.perf_counter()
  for _ in range(calls):
    x = f(x)
  jax.block_until_ready(x)
  return x, (time.perf_counter() - t0) / calls


def env_steps(t, n: int, tasks, length: int):
  """length control steps of every run's environments at zero action, one program (no learning)."""
  env = t.learner.env
  zeros = jnp.zeros((n, t.plan.num_envs, env.action_size))

  def body(s, _):
    if tasks is None:
      return jax.vmap(env.step)(s, zeros), ()
    return jax.vmap(lambda st, a, d: learner_on(t, d).env.step(st, a))(s, zeros, tasks), ()
  return jax.jit(lambda s: jax.lax.scan(body, s, (), length=length)[0])


def trace_summary(folder: pathlib.Path, control_steps: int, wall_s: float) -> dict:
  """Kernels per control step, device-busy time, device-to-host copies and the top kernels of the
  perfetto trace jax.profiler wrote under `folder`."""
  path = max(folder.rglob("perfetto_trace.json.gz"), key=lambda p: p.stat().st_mtime)
  events = json.load(gzip.open(path))
  events = events["traceEvents"] if isinstance(events, dict) else events
  names = {e["pid"]: e["args"].get("name", "") for e in events if e.get("ph") == "M" and e.get("name") == "process_name"}
  device = {pid for pid, name in names.items() if "/device:" in name and "CPU" not in name.split("/device:")[-1]}
  on_device = [e for e in events if e.get("ph") == "X" and e.get("pid") in device]
  by_name, calls = collections.Counter(), collections.Counter()
  for e in on_device:
    by_name[e["name"]] += float(e.get("dur", 0))
    calls[e["name"]] += 1
  copies = [e for e in on_device if "memcpy" in e["name"].lower() and any(
      w in e["name"].lower().replace(" ", "") for w in ("dtoh", "d2h"))]
  busy_us = sum(float(e.get("dur", 0)) for e in on_device)
  return {"device_processes": sorted(names[p] for p in device), "events_on_device": len(on_device),
          "per_control_step": {"events": len(on_device) / control_steps, "device_to_host_copies": len(copies) / control_steps,
                               "device_busy_ms": busy_us / 1e3 / control_steps, "wall_ms": wall_s * 1e3 / control_steps},
          "top_kernels_per_control_step": {k: {"ms": round(v / 1e3 / control_steps, 4), "calls": calls[k] / control_steps,
                                                   "us_per_call": round(v / calls[k], 2)}
                                               for k, v in by_name.most_common(15)}}


def measure(argv: list[str], n: int, updates: int, out: pathlib.Path) -> dict:
  plans = plans_of(argv, n)
  t = build_group(plans)
  tasks = group_tasks(t, plans)
  t0 = time.time()
  compiled = lower_group(t, n, tasks).compile()
  compile_s = time.time() - t0
  update = compiled if tasks is None else (lambda s: compiled(s, tasks))
  steps = t.learner.steps_per_update // t.plan.num_envs  # control steps of each environment per update
  states, per_update = seconds_per_call(lambda s: update(s)[0], init_group(t, plans, tasks), updates)
  folder = out / f"trace-{n}"
  with jax.profiler.trace(str(folder), create_perfetto_trace=True):
    t1 = time.perf_counter()
    states = jax.block_until_ready(update(states)[0])
    traced_s = time.perf_counter() - t1
  physics = env_steps(t, n, tasks, steps)
  _, env_per_call = seconds_per_call(physics, states.env_state, updates)
  return {"runs": n, "robots_per_run": t.plan.num_envs, "compile_s": round(compile_s, 1),
          "control_steps_per_update": steps, "training_ms_per_control_step": round(per_update * 1e3 / steps, 3),
          "env_only_ms_per_control_step": round(env_per_call * 1e3 / steps, 3),
          "traced_update": trace_summary(folder, steps, traced_s), **evaluation(t, plans, tasks, states, out / f"trace-eval-{n}")}


def evaluation(t, plans, tasks, states, folder: pathlib.Path) -> dict:
  """The program's Brax evaluation (train.core.group.group_evaluations): its first call (with the
  compilation), a second one timed, a third profiled; {} where the preset has none or the runs
  are evaluated one by one."""
  shared, _ = group_evaluations(t, plans, None if tasks is None else [p.cfg for p in plans])
  if shared is None:
    return {}
  t0 = time.perf_counter()
  shared.evaluate(states)
  first = time.perf_counter() - t0
  t0 = time.perf_counter()
  shared.evaluate(states)
  second = time.perf_counter() - t0
  length = t.plan.cfg.episode.max_steps
  with jax.profiler.trace(str(folder), create_perfetto_trace=True):
    t0 = time.perf_counter()
    shared.evaluate(states)
    third = time.perf_counter() - t0
  return {"evaluation": {"episodes_per_run": t.plan.preset.num_eval_envs, "control_steps": length,
                         "first_s": round(first, 2), "second_s": round(second, 2),
                         "traced": trace_summary(folder, length, third)}}


def main() -> int:
  argv = sys.argv[1:]
  ours, train_argv = (argv[:argv.index("--")], argv[argv.index("--") + 1:]) if "--" in argv else (argv, [])
  p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
  p.add_argument("out")
  p.add_argument("--runs", default="1,20,40", help="runs per program, one program after another")
  p.add_argument("--updates", type=int, default=4, help="training steps timed per program (after one untimed)")
  a = p.parse_args(ours)
  out = pathlib.Path(a.out)
  out.mkdir(parents=True, exist_ok=True)
  result = {"device": str(jax.devices()[0].device_kind), "jax": jax.__version__,
            "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "command": "python scripts/gpu/profile_group.py " + " ".join(argv), "programs": []}
  for n in [int(x) for x in a.runs.split(",")]:
    result["programs"].append(measure(train_argv, n, a.updates, out))
    print(json.dumps(result["programs"][-1], indent=1), flush=True)
    (out / "profile-group.json").write_text(json.dumps(result, indent=1) + "\n")
  return 0


if __name__ == "__main__":
  sys.exit(main())

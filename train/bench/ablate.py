"""ablate: where the environment step's time goes: full env throughput of the task under config
variants, side by side in one process, with each variant's speed-up over the first."""

from __future__ import annotations

import json

from train.bench.timing import time_env_step

VARIANTS = {  # name -> config overrides; the first is the reference
    "every contact kept (before culling)": ("physics.contact_slots=-1", "physics.box_pairs=-1"),
    "48 contact slots": ("physics.box_pairs=-1",),
    "22 box pairs": ("physics.contact_slots=-1",),
    "default (48 slots, 22 pairs)": (),
    "32 contact slots": ("physics.contact_slots=32",),
    "no beams": ("observation.parts=[v, flippers_paired, arm, pitch]",),
    "2 solver iterations": ("physics.solver_iterations=2",),
    "3 line-search iterations": ("physics.ls_iterations=3",),
    "timestep 0.0125 s (20 substeps)": ("physics.timestep=0.0125",),
}


def add_args(p) -> None:
  p.add_argument("--task", default="asc-inc-cog")
  p.add_argument("--envs", type=int, default=16384)
  p.add_argument("--reps", type=int, default=5)
  p.add_argument("--variant", action="append", default=[], metavar="NAME:KEY=VALUE;KEY=VALUE",
                 help="a variant (replaces the built-in list; the first is the reference)")


def parse_variant(text: str) -> tuple[str, tuple[str, ...]]:
  """'NAME:KEY=VALUE;KEY=VALUE' -> (NAME, overrides)."""
  name, _, overrides = text.partition(":")
  return name, tuple(o for o in overrides.split(";") if o)


def measure(task: str, overrides: tuple[str, ...], n: int, reps: int) -> dict:
  """Control steps/s of n robots under the overrides, and the compile time."""
  import mjx_tracks  # noqa: PLC0415
  from mjx_tracks.sim import mjx_private  # noqa: PLC0415
  core = mjx_tracks.load(task, overrides)
  state, compile_s, step_s = time_env_step(core, n, reps)
  return {"control_steps_per_s": round(n / step_s), "compile_s": round(compile_s, 1),
          "substeps": core.substeps, "constraint_rows": mjx_private.efc_rows(state.pipeline_state.data)}


def run(args) -> tuple[list[dict], dict]:
  variants = dict(parse_variant(v) for v in args.variant) if args.variant else VARIANTS
  rows, base = [], None
  for name, overrides in variants.items():
    row = {"variant": name, "overrides": list(overrides), "envs": args.envs,
           **measure(args.task, overrides, args.envs, args.reps)}
    base = base or row["control_steps_per_s"]
    row["speedup"] = round(row["control_steps_per_s"] / base, 3)
    rows.append(row)
    print(json.dumps(row), flush=True)
  return rows, {"task": args.task}

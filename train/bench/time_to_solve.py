"""time-to-solve: from process start to an exported policy that reaches the success threshold on
the task's probe scene (the hardest configuration; random areas for navigation), per seed:
`python -m train.run --early-stop success=X` (each seed in its own process with its own empty
compilation cache, so every process compiles from scratch), then `python -m train.evaluate --scene
SCENE` of its policy (the same trials as the in-training probe).
Seeds run one after another on this machine's devices."""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile

from mjx_tracks.envs.config import load_config
from train.bench.timing import process_wall_s
from train.core.early_stop import EARLY_STOP_SUCCESS


def add_args(p) -> None:
  p.add_argument("--task", default="asc-inc-cog")
  p.add_argument("--seeds", default="0,1,2", help="comma-separated")
  p.add_argument("--steps", type=int, default=4_000_000, help="budget if the threshold is never reached")
  p.add_argument("--preset", help="train.run's --preset (default: its own)")
  p.add_argument("--threshold", type=float, default=EARLY_STOP_SUCCESS, help="success to reach (default %(default)s)")
  p.add_argument("--work", help="folder for the runs (default: a new temporary one)")


def _solve(args, seed: int, work: str) -> dict:
  """One seed: the run's process wall time, where and why it stopped, and its success on the probe scene."""
  from train.db import ExperimentDB  # noqa: PLC0415
  from train.core.run_record import read_run_record  # noqa: PLC0415
  out, db, cache = (os.path.join(work, f"s{seed}{x}") for x in ("", ".sqlite", "-cache"))
  train = [sys.executable, "-m", "train.run", "--task", args.task, "--steps", str(args.steps), "--early-stop",
           f"success={args.threshold}", "--seed", str(seed), "--out", out, "--db", db, *(["--preset", args.preset] if args.preset else [])]
  rc, wall = process_wall_s(train, cache)
  row = {"seed": seed, "rc": rc, "process_wall_s": round(wall, 1), "command": " ".join(train[1:])}
  if rc != 0:
    return {**row, "reason": "failed"}
  final = json.loads(ExperimentDB(db).run(read_run_record(out)["run_id"])["final_json"] or "{}")
  scene = load_config(args.task).scene.probe_scene
  report = os.path.join(work, f"s{seed}-eval-{scene}.json")
  subprocess.check_call([sys.executable, "-m", "train.evaluate", out, "--scene", scene, "--out", report, "--db", db])
  success = json.load(open(report))["metrics"]["success"]["mean"]
  return {**row, "step": final.get("step"), "reason": final.get("reason"), "scene": scene, "success": success}


def run(args) -> tuple[list[dict], dict]:
  work = args.work or tempfile.mkdtemp(prefix="time-to-solve-")
  rows = []
  for seed in (int(s) for s in args.seeds.split(",")):
    rows.append(_solve(args, seed, work))
    print(json.dumps(rows[-1]), flush=True)
  solved = [r["process_wall_s"] for r in rows if (r.get("success") or 0) >= args.threshold]
  median = statistics.median(solved) if solved and len(solved) == len(rows) else None
  return rows, {"task": args.task, "success_threshold": args.threshold, "budget_steps": args.steps,
                "median_process_wall_s": median, "solved_seeds": len(solved)}

"""A stand-in for `train.run` / `train.evaluate` in study tests (no JAX): `train ARGS` makes a run
folder with a checkpoint every 100 steps (0.1 s each) and records the run and one statistics row per
checkpoint in its database (with --seeds S,S,..., one folder OUT/s<seed> per seed, with --tasks T,T,...
OUT/<task>/s<seed>, with --early-stops C,C,... OUT/stop-<criterion>/... (train.core.run_record.seed_folder),
side by side; each run.json lists its sessions' seeds (and tasks, early stops) under "programs"); `evaluate RUN --suite --trials N [--milestones]` records N trials per
scene of fake_success() and writes eval-hardest.json (with several RUNs, each) (with --baseline NAME --task TASK, first a run
record of its own; with --await-runs, started beside the training, only the RUNs that stdin names once it closes). FAKE_CRASH_SEED: that seed's first session
exits 1 after its checkpoint at FAKE_CRASH_STEP (default 100); FAKE_EARLY_SEED: that seed's run stops
early at step 200 (status stopped_early); FAKE_SLOW_SEED: that seed sleeps 1 s per checkpoint (time to
kill its worker); SIGTERM ends a session like train.run's: run 'interrupted', exit 143."""

import argparse
import json
import os
import signal
import sys
import time

from train.core.run_record import seed_folder
from train.db import ExperimentDB

SCENES = ("hardest", "uniform", "held-out/middle")


def fake_success(task: str, seed: int, budget: int, trial: int) -> int:
  """Trial outcomes: 'inc' tasks succeed in (seed + 2) of every 4 trials, others in seed + 1; the
  last budget adds one more of every 4 (capped at 4)."""
  per4 = (seed + 2 if "-inc-" in task else seed + 1) + (1 if budget >= 400 else 0)
  return int(trial % 4 < min(per4, 4))


def _begin(a, out: str, seed: str, task: str, db: ExperimentDB) -> dict:
  """A run's record (new, or read to resume), its session counted and its start recorded."""
  meta_path = os.path.join(out, "run.json")
  if a.resume:
    meta = json.load(open(meta_path))
  else:
    meta = {"run_id": f"{task}-s{seed}-{time.time_ns()}", "task": task, "seed": int(seed),
            "steps": int(a.steps), "total_steps": int(a.steps), "sessions": 0, "milestones": [int(m) for m in (a.milestones or "").split(",") if m]}
  meta["sessions"] += 1
  # the seeds (and tasks, early stops) each session trained in one process
  program = a.seeds + "".join(f" x {x}" for x in (a.tasks, a.early_stops) if x) if a.seeds else str(meta["seed"])
  meta.setdefault("programs", []).append(program)
  db.start(meta["run_id"], meta["task"], "ppo", "cpu", meta["seed"], {}, out, meta["steps"])
  db.compiled(meta["run_id"], 0, 0.0)  # as train.run records its training step's compilation (none here)
  os.makedirs(os.path.join(out, "checkpoints"), exist_ok=True)
  json.dump(meta, open(meta_path, "w"))
  return meta


EARLY_STEP = 200  # where FAKE_EARLY_SEED's run stops early


def _step(meta: dict, out: str, db: ExperimentDB) -> bool:
  """One checkpoint further (if its run goes on); False if the run crashes there."""
  step = max([int(d) for d in os.listdir(os.path.join(out, "checkpoints"))], default=0)
  if not _goes_on(meta, step):
    return True
  time.sleep(1.0 if str(meta["seed"]) == os.environ.get("FAKE_SLOW_SEED") else 0.1)
  step += 100
  os.makedirs(os.path.join(out, "checkpoints", str(step)))
  if step in meta["milestones"]:
    os.makedirs(os.path.join(out, "milestones", str(step)))
  db.log_stats(meta["run_id"], {"step": step, "wall_s": step / 100, "return_mean": step / 1000 + meta["seed"],
                                "success_rate": step / 1000, "source": "train"}, {})
  if not _goes_on(meta, step):
    db.finish(meta["run_id"], "done" if step >= meta["steps"] else "stopped_early", {}, step)
  crash_step = int(os.environ.get("FAKE_CRASH_STEP", "100"))
  return not (str(meta["seed"]) == os.environ.get("FAKE_CRASH_SEED") and meta["sessions"] == 1 and step >= crash_step)


def _goes_on(meta: dict, step: int) -> bool:
  """Whether a run at `step` trains further: not at its total steps nor at its early stop."""
  early = str(meta["seed"]) == os.environ.get("FAKE_EARLY_SEED") and step >= EARLY_STEP
  return step < meta["steps"] and not early


def train(argv: list[str]) -> int:
  """One run (--seed), or several side by side in OUT/s<seed> (--seeds S,S,...; with --tasks T,T,...
  OUT/<task>/s<seed>, with --early-stops OUT/stop-<criterion>/...) with one database."""
  p = argparse.ArgumentParser()
  for name in ("--task", "--tasks", "--algo", "--preset", "--steps", "--seed", "--seeds", "--out", "--db", "--resume",
               "--early-stop", "--early-stops", "--milestones"):
    p.add_argument(name)
  p.add_argument("--set", action="append", default=[])
  a = p.parse_args(argv)
  db = ExperimentDB(a.db)
  if a.resume:
    runs = [(a.resume, a.seed, json.load(open(os.path.join(a.resume, "run.json")))["task"])]
  elif a.seeds:
    tasks, stops = (a.tasks or a.task).split(","), (a.early_stops or a.early_stop).split(",")
    runs = [(seed_folder(a.out, s, t if a.tasks else None, stop if a.early_stops else None), s, t)
            for stop in stops for t in tasks for s in a.seeds.split(",")]
  else:
    runs = [(a.out, a.seed, a.task)]
  metas = [(_begin(a, out, seed, task, db), out) for out, seed, task in runs]

  def interrupted(*_):
    for meta, _ in metas:
      db.finish(meta["run_id"], "interrupted", {})
    sys.exit(143)

  signal.signal(signal.SIGTERM, interrupted)
  while any(_goes_on(meta, 100 * len(os.listdir(os.path.join(out, "checkpoints")))) for meta, out in metas):
    for meta, out in metas:
      if not _step(meta, out, db):
        return 1
  return 0


def evaluate(argv: list[str]) -> int:
  """Each RUN given before the options (a pack's runs together), or a baseline's folder; with
  --await-runs those of them that stdin names."""
  runs = argv[:next(i for i, a in enumerate(argv) if a.startswith("--"))]
  if "--await-runs" in argv:
    named = [line.strip() for line in sys.stdin if line.strip()]
    assert set(named) <= set(runs), (named, runs)
    print(f"evaluating {len(named)} of {len(runs)} runs beside the training (named on stdin)")
    runs = named
  return max((evaluate_one(out, argv) for out in runs), default=0)


def evaluate_one(out: str, argv: list[str]) -> int:
  trials = int(argv[argv.index("--trials") + 1])
  db = ExperimentDB(argv[argv.index("--db") + 1])
  if "--baseline" in argv:  # a baseline: a run record of its own, nothing trained
    name, task = argv[argv.index("--baseline") + 1], argv[argv.index("--task") + 1]
    meta = {"run_id": f"{task}-baseline-{name}", "task": task, "seed": 0, "steps": 0, "milestones": []}
    os.makedirs(out, exist_ok=True)
    json.dump(meta, open(os.path.join(out, "run.json"), "w"))
    db.start(meta["run_id"], task, "baseline", name, 0, {}, out, 0)
    db.finish(meta["run_id"], "done", {}, 0)
  meta = json.load(open(os.path.join(out, "run.json")))
  budgets = [*meta["milestones"], None] if "--milestones" in argv else [None]
  for budget in budgets:
    for scene in SCENES:
      rows = [{"scene": scene, "budget": budget, "trial": i, "progress": 0.5, "cog_deviation": 0.1,
               "pitch_rate": 0.2, "tipped_over": 0, "length": 10, "collided": 0,
               "success": fake_success(meta["task"], meta["seed"], budget or meta["steps"], i)} for i in range(trials)]
      db.log_evals(meta["run_id"], rows, replace=(scene, budget))
  json.dump({"metrics": {"success": {"mean": 1.0}}}, open(os.path.join(out, "eval-hardest.json"), "w"))
  return 0


if __name__ == "__main__":
  sys.exit(train(sys.argv[2:]) if sys.argv[1] == "train" else evaluate(sys.argv[2:]))

"""What a benchmark reads of the training runs it started: their training rates and how long their
training step compiled, from the runs' database (train.db), never from their printed output. Used
by the GPU drivers (scripts/gpu/compile_flags.py, scripts/gpu/mps_pair.sh)."""

from __future__ import annotations

import datetime
import os
import statistics

from train.db import TRAIN_SOURCE, ExperimentDB


def _db(db_path: str) -> ExperimentDB:
  if not os.path.isfile(db_path):  # ExperimentDB would make an empty one
    raise FileNotFoundError(f"no run database at {db_path}")
  return ExperimentDB(db_path)


def training_rates(db_path: str) -> list[dict]:
  """Per report step of the database's runs, in step order: {step, clock_s: the latest run's wall
  time (s) at that step, steps_per_s: the median over the runs of their training steps/s (the loop's:
  evaluations and checkpoints excluded)}."""
  db, by_step = _db(db_path), {}
  for run in db.runs():
    for row in db.stats(run["run_id"]):
      if row["source"] == TRAIN_SOURCE and row["steps_per_s"] is not None:
        by_step.setdefault(row["step"], []).append((row["steps_per_s"], row["wall_s"]))
  return [{"step": step, "clock_s": max(wall for _, wall in rows), "steps_per_s": statistics.median(r for r, _ in rows)}
          for step, rows in sorted(by_step.items())]


def steady_rate(rates: list[dict]) -> float | None:
  """The median steps/s of training_rates' reports after the first (whose window holds the first
  update's start-up), or None with fewer than two reports."""
  later = [r["steps_per_s"] for r in rates[1:]]
  return statistics.median(later) if later else None


def _compiled_events(db_path: str) -> list[dict]:
  db = _db(db_path)
  return [e for run in db.runs() for e in db.events(run["run_id"]) if e["event"] == "compiled"]


def compile_seconds(db_path: str) -> float | None:
  """The longest a training step of the database's runs took to compile (s; the runs of one program
  share one), or None where none was recorded."""
  seconds = [float(e["detail"]) for e in _compiled_events(db_path)]
  return max(seconds) if seconds else None


def compiled_at(db_path: str) -> float | None:
  """When the database's runs first had their training step compiled (epoch s, whole seconds as the
  database records them): when their training started; None where none was recorded."""
  times = [datetime.datetime.fromisoformat(e["time"]).timestamp() for e in _compiled_events(db_path)]
  return min(times) if times else None

"""A run's record, RUN_DIR/run.json: written by train.run (atomically), read here by everything else
(resume, evaluation, the database CLI, studies). One reader: one set of checks and messages."""

from __future__ import annotations

import json
import os

from mjx_tracks import atomic

RUN_JSON = "run.json"
REQUIRED = ("run_id", "task", "algo", "config")  # what every record holds


def run_json_path(run_dir: str) -> str:
  return os.path.join(run_dir, RUN_JSON)


def is_run_dir(path: str) -> bool:
  return os.path.isdir(path) and os.path.exists(run_json_path(path))


def read_run_record(run_dir: str, required: tuple[str, ...] = REQUIRED) -> dict:
  """RUN_DIR/run.json; FileNotFoundError if there is none (not a run directory), ValueError in one
  line if it is unreadable or lacks a required key (not a run's record)."""
  path = run_json_path(run_dir)
  if not os.path.exists(path):
    raise FileNotFoundError(f"{run_dir} is not a run directory (no {RUN_JSON})")
  try:
    with open(path) as f:
      meta = json.load(f)
  except (OSError, ValueError) as e:
    raise ValueError(f"{path} is not readable JSON ({str(e).splitlines()[0][:120]})") from None
  missing = [k for k in required if not isinstance(meta, dict) or k not in meta]
  if missing:
    raise ValueError(f"{path} is not a run's record (no {', '.join(missing)})")
  return meta


def seed_folder(out: str, seed: int, task: str | None = None, early_stop: str | None = None) -> str:
  """The folder of seed `seed`'s run among the runs of one program (train.run --seeds S,... --out
  OUT): OUT/s<seed>; in a program of several tasks (--tasks; task given) OUT/<task>/s<seed>; in a
  program of several early stops (--early-stops; early_stop given: the criterion as written)
  OUT/stop-<criterion>/... in front of either."""
  if early_stop is not None:
    out = os.path.join(out, f"stop-{early_stop}")
  return os.path.join(out, f"s{seed}") if task is None else os.path.join(out, task, f"s{seed}")


def several_tasks(runs) -> bool:
  """Whether the runs of one program (anything with a `task`: plans, a study's cells) are of several
  tasks: then each run's folder is OUT/<task>/s<seed> (seed_folder) and train.run takes --tasks."""
  return len({r.task for r in runs}) > 1


def several_stops(stops) -> bool:
  """Whether the runs of one program stop at several criteria (each run's early stop as written, e.g.
  "return", "none"): then each run's folder is OUT/stop-<criterion>/... (seed_folder) and train.run
  takes --early-stops."""
  return len(set(stops)) > 1


def run_id_in(run_dir: str) -> str | None:
  """The run id a run folder records, if it has a readable record yet."""
  try:
    return read_run_record(run_dir, ("run_id",))["run_id"]
  except (FileNotFoundError, ValueError):
    return None


def run_config(run_dir: str):
  """The task config (validated) a run recorded."""
  from mjx_tracks.envs.config import from_dict  # noqa: PLC0415
  return from_dict(read_run_record(run_dir)["config"])


def write_run_record(run_dir: str, meta: dict) -> None:
  """RUN_DIR/run.json, atomically."""
  os.makedirs(run_dir, exist_ok=True)
  atomic.write_json(run_json_path(run_dir), meta)

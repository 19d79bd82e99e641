"""Embedded experiment database (SQLite): experiments, training statistics, evaluation trials.

python -m train.db [--db PATH] list
python -m train.db [--db PATH] show RUN
python -m train.db [--db PATH] export RUN --csv [--out FILE]

Concurrent runs may share one file: WAL journaling and a busy timeout serialize the writers.
A run whose process died without closing is shown as 'crashed'.
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import datetime
import json
import os
import socket
import sqlite3
import sys
from typing import Any, Iterator

DEFAULT_ROOT = "runs"
DEFAULT_NAME = "experiments.sqlite"

SCHEMA = """
CREATE TABLE IF NOT EXISTS experiments (
  run_id TEXT PRIMARY KEY, task TEXT NOT NULL, algo TEXT NOT NULL, preset TEXT, seed INTEGER,
  config_json TEXT NOT NULL, status TEXT NOT NULL, started TEXT NOT NULL, ended TEXT,
  out_dir TEXT NOT NULL, checkpoint_dir TEXT, pid INTEGER, host TEXT, total_steps INTEGER,
  final_json TEXT
);
CREATE TABLE IF NOT EXISTS stats (
  run_id TEXT NOT NULL REFERENCES experiments(run_id), step INTEGER NOT NULL, wall_s REAL,
  steps_per_s REAL, eps REAL, return_mean REAL, progress_mean REAL, cog_deviation_mean REAL,
  pitch_rate_mean REAL, tipped_rate REAL, success_rate REAL, metrics_json TEXT
);
CREATE INDEX IF NOT EXISTS stats_run ON stats(run_id, step);
CREATE TABLE IF NOT EXISTS evals (
  run_id TEXT NOT NULL REFERENCES experiments(run_id), scene TEXT NOT NULL, trial INTEGER NOT NULL,
  progress REAL, success INTEGER, cog_deviation REAL, pitch_rate REAL, tipped_over INTEGER,
  length INTEGER, created TEXT
);
"""
STAT_COLUMNS = ("step", "wall_s", "steps_per_s", "eps", "return_mean", "progress_mean",
                "cog_deviation_mean", "pitch_rate_mean", "tipped_rate", "success_rate")
EVAL_COLUMNS = ("scene", "trial", "progress", "success", "cog_deviation", "pitch_rate",
                "tipped_over", "length")


def _now() -> str:
  return datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")


def _pid_alive(pid: int | None) -> bool:
  if not pid:
    return False
  try:
    os.kill(pid, 0)
  except ProcessLookupError:
    return False
  except PermissionError:
    return True
  return True


class ExperimentDB:
  """Thin API over the SQLite file; every call opens its own short transaction."""

  def __init__(self, path: str):
    self.path = path
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with self._conn() as c:
      c.executescript(SCHEMA)

  @contextlib.contextmanager
  def _conn(self) -> Iterator[sqlite3.Connection]:
    c = sqlite3.connect(self.path, timeout=30.0)
    try:
      c.execute("PRAGMA journal_mode=WAL")
      c.execute("PRAGMA busy_timeout=30000")
      c.row_factory = sqlite3.Row
      with c:
        yield c
    finally:
      c.close()

  # --- writing ----------------------------------------------------------------------------
  def start(self, run_id: str, task: str, algo: str, preset: str, seed: int, config: dict,
            out_dir: str, total_steps: int) -> None:
    """Inserts a run, or marks a resumed one running again."""
    with self._conn() as c:
      row = c.execute("SELECT run_id FROM experiments WHERE run_id = ?", (run_id,)).fetchone()
      if row:
        c.execute("UPDATE experiments SET status='running', pid=?, host=?, ended=NULL WHERE run_id=?",
                  (os.getpid(), socket.gethostname(), run_id))
      else:
        c.execute("INSERT INTO experiments (run_id, task, algo, preset, seed, config_json, status, "
                  "started, out_dir, pid, host, total_steps) VALUES (?,?,?,?,?,?,?,?,?,?,?,?)",
                  (run_id, task, algo, preset, seed, json.dumps(config), "running", _now(),
                   os.path.abspath(out_dir), os.getpid(), socket.gethostname(), total_steps))

  def log_stats(self, run_id: str, row: dict[str, Any], metrics: dict[str, float]) -> None:
    vals = [row.get(k) for k in STAT_COLUMNS]
    with self._conn() as c:
      c.execute(f"INSERT INTO stats (run_id, {', '.join(STAT_COLUMNS)}, metrics_json) "
                f"VALUES (?, {', '.join('?' * len(STAT_COLUMNS))}, ?)",
                [run_id, *vals, json.dumps(metrics)])

  def set_checkpoint(self, run_id: str, checkpoint_dir: str) -> None:
    with self._conn() as c:
      c.execute("UPDATE experiments SET checkpoint_dir=? WHERE run_id=?", (checkpoint_dir, run_id))

  def finish(self, run_id: str, status: str, final: dict | None = None) -> None:
    with self._conn() as c:
      c.execute("UPDATE experiments SET status=?, ended=?, final_json=? WHERE run_id=?",
                (status, _now(), json.dumps(final or {}), run_id))

  def log_evals(self, run_id: str, trials: list[dict[str, Any]]) -> None:
    with self._conn() as c:
      c.executemany(f"INSERT INTO evals (run_id, {', '.join(EVAL_COLUMNS)}, created) "
                    f"VALUES (?, {', '.join('?' * len(EVAL_COLUMNS))}, ?)",
                    [[run_id, *[t.get(k) for k in EVAL_COLUMNS], _now()] for t in trials])

  # --- reading ----------------------------------------------------------------------------
  def runs(self) -> list[dict[str, Any]]:
    """All experiments; a 'running' row whose process is gone on this host reads 'crashed'."""
    with self._conn() as c:
      rows = [dict(r) for r in c.execute("SELECT * FROM experiments ORDER BY started")]
    host = socket.gethostname()
    for r in rows:
      if r["status"] == "running" and r["host"] == host and not _pid_alive(r["pid"]):
        r["status"] = "crashed"
    return rows

  def run(self, run_id: str) -> dict[str, Any]:
    for r in self.runs():
      if r["run_id"] == run_id:
        return r
    raise KeyError(f"no run {run_id!r} in {self.path}")

  def stats(self, run_id: str) -> list[dict[str, Any]]:
    with self._conn() as c:
      return [dict(r) for r in c.execute("SELECT * FROM stats WHERE run_id=? ORDER BY step", (run_id,))]

  def evals(self, run_id: str) -> list[dict[str, Any]]:
    with self._conn() as c:
      return [dict(r) for r in c.execute("SELECT * FROM evals WHERE run_id=? ORDER BY scene, trial", (run_id,))]


def default_path(out_root: str = DEFAULT_ROOT) -> str:
  return os.path.join(out_root, DEFAULT_NAME)


def main(argv: list[str] | None = None) -> int:
  p = argparse.ArgumentParser(prog="python -m train.db", description=__doc__.splitlines()[0])
  p.add_argument("--db", default=default_path(), help=f"SQLite file (default {default_path()})")
  sub = p.add_subparsers(dest="cmd", required=True)
  sub.add_parser("list", help="one line per experiment")
  s = sub.add_parser("show", help="an experiment's row, last statistics and evaluations")
  s.add_argument("run")
  e = sub.add_parser("export", help="an experiment's training statistics")
  e.add_argument("run")
  e.add_argument("--csv", action="store_true", required=True)
  e.add_argument("--out", help="file (default: standard output)")
  args = p.parse_args(argv)
  if not os.path.exists(args.db):
    print(f"error: no database at {args.db}", file=sys.stderr)
    return 2
  db = ExperimentDB(args.db)
  if args.cmd == "list":
    for r in db.runs():
      final = json.loads(r["final_json"] or "{}")
      print(f"{r['run_id']:40s} {r['task']:12s} {r['algo']:4s} {r['status']:8s} {r['started']}  "
            f"steps={final.get('step', '-')} return={final.get('return_mean', '-')}")
    return 0
  try:
    run = db.run(args.run)
  except KeyError as err:
    print(f"error: {err.args[0]}", file=sys.stderr)
    return 2
  if args.cmd == "show":
    print(json.dumps({k: v for k, v in run.items() if k != "config_json"}, indent=1))
    stats = db.stats(args.run)
    if stats:
      print("last statistics:", json.dumps({k: stats[-1][k] for k in STAT_COLUMNS}))
    for scene in sorted({e["scene"] for e in db.evals(args.run)}):
      trials = [e for e in db.evals(args.run) if e["scene"] == scene]
      mean = lambda k: sum(t[k] for t in trials) / len(trials)
      print(f"eval {scene}: {len(trials)} trials, progress {mean('progress'):.3f}, "
            f"success {mean('success'):.2f}, tipped {mean('tipped_over'):.2f}")
    return 0
  out = open(args.out, "w", newline="") if args.out else sys.stdout
  w = csv.writer(out)
  w.writerow(STAT_COLUMNS)
  for r in db.stats(args.run):
    w.writerow([r[k] for k in STAT_COLUMNS])
  if args.out:
    out.close()
  return 0


if __name__ == "__main__":
  sys.exit(main())

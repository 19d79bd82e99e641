"""Embedded experiment database (SQLite): experiments, their events, training statistics,
evaluation trials.

python -m train.db [--db PATH] list
python -m train.db [--db PATH] show RUN          (RUN: a run id or a run directory)
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
import time
from typing import Any, Iterator

import numpy as np

from mjx_tracks.metrics import EPISODE, EPISODE_NAMES, REPORT_COLUMN

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
  steps_per_s REAL, eps REAL, return_mean REAL, {report_columns}, metrics_json TEXT, source TEXT
);
CREATE INDEX IF NOT EXISTS stats_run ON stats(run_id, step);
CREATE TABLE IF NOT EXISTS events (
  run_id TEXT NOT NULL REFERENCES experiments(run_id), event TEXT NOT NULL, step INTEGER,
  time TEXT NOT NULL, detail TEXT
);
CREATE TABLE IF NOT EXISTS evals (
  run_id TEXT NOT NULL REFERENCES experiments(run_id), scene TEXT NOT NULL, trial INTEGER NOT NULL,
  {trial_columns}, created TEXT, budget INTEGER
);
CREATE TABLE IF NOT EXISTS launches (
  id INTEGER PRIMARY KEY AUTOINCREMENT, kind TEXT NOT NULL, spec_json TEXT NOT NULL, status TEXT NOT NULL,
  out_dir TEXT, created TEXT NOT NULL, started TEXT, ended TEXT, rc INTEGER, error TEXT
);
CREATE TABLE IF NOT EXISTS attempts (
  study TEXT NOT NULL, cell TEXT NOT NULL, attempt INTEGER NOT NULL, run_id TEXT, worker TEXT,
  started REAL, ended REAL, rc INTEGER, phase TEXT, resumed INTEGER, error TEXT,
  PRIMARY KEY (study, cell, attempt)
);
"""
SCHEMA = SCHEMA.format(  # the metric columns: mjx_tracks.metrics
    report_columns=", ".join(f"{c} REAL" for c in REPORT_COLUMN.values()),
    trial_columns=", ".join(f"{m.name} {'INTEGER' if m.integer else 'REAL'}" for m in EPISODE))
STAT_COLUMNS = ("step", "wall_s", "steps_per_s", "eps", "return_mean", *REPORT_COLUMN.values(), "source")
STAT_SOURCES = ("train", "eval", "probe")  # training episodes, Brax's evaluator (uniform scenes), train.core.probe
TRAIN_SOURCE = STAT_SOURCES[0]  # the stats rows of training reports (not evaluations or probes)
OLD_SOURCES = {"hardest": "probe"}  # a source's name in databases written before it was renamed
# "compiled": the training step compiled (its detail: the seconds until it was ready, e.g. "34.215", a wait for
# another process compiling it included: mjx_tracks.jax_private; train.bench.runs reads it)
EVENTS = ("started", "resumed", "compiled", "checkpoint", "finished", "interrupted", "failed", "crashed")
# a run's final status -> the event that records it
STATUS_EVENT = {"done": "finished", "stopped_early": "finished", "interrupted": "interrupted",
                "failed": "failed", "crashed": "crashed"}
FINISHED = tuple(s for s, event in STATUS_EVENT.items() if event == "finished")  # a training that ended as it should
EVAL_COLUMNS = ("scene", "budget", "trial", *EPISODE_NAMES)  # budget: the milestone of the policy (train.run --milestones); NULL: final
# columns a database written before they existed may lack: table -> (column, type); every metric
# column, so a metric added to mjx_tracks.metrics reaches old databases too (NULL in their old rows)
ADDED_COLUMNS = {"stats": (("source", "TEXT"), *((c, "REAL") for c in REPORT_COLUMN.values())),
                 "evals": (("budget", "INTEGER"), *((m.name, "INTEGER" if m.integer else "REAL") for m in EPISODE))}


def utc_now() -> str:
  """The current UTC time, ISO 8601 to the second: every time the database records."""
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


@contextlib.contextmanager
def read_only(path: str) -> Iterator[sqlite3.Connection]:
  """A read-only connection to an existing database file (never creates one), closed on exit. A file
  no process is writing (no write-ahead log beside it: a finished or committed study's) is opened
  immutable, so reading it leaves no -wal / -shm files beside it."""
  live = os.path.exists(path + "-wal")
  c = sqlite3.connect(f"file:{path}?mode=ro" + ("" if live else "&immutable=1"), uri=True)
  try:
    yield c
  finally:
    c.close()


WAL_TRIES, WAL_WAIT = 100, 0.05  # tries, s between them: how long a new file's first openers wait for each other


def _write_ahead_log(c: sqlite3.Connection) -> None:
  """The file in WAL mode (kept in the file, so set once). Switching needs the file to itself, and
  SQLite answers "database is locked" at once, without its busy timeout, while another process is
  opening the same new file: processes started together on one new database (a study's evaluations,
  scripts/gpu/harsh_grid.sh) crashed there (how often: tests/test_db.py). Retried for up to WAL_TRIES x WAL_WAIT s."""
  for attempt in range(WAL_TRIES):
    try:
      if c.execute("PRAGMA journal_mode").fetchone()[0].lower() != "wal":
        c.execute("PRAGMA journal_mode=WAL")
      return
    except sqlite3.OperationalError as e:
      if "locked" not in str(e) or attempt == WAL_TRIES - 1:
        raise
      time.sleep(WAL_WAIT)


class ExperimentDB:
  """Thin API over the SQLite file; every call opens its own short transaction."""

  def __init__(self, path: str):
    self.path = path
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with self._conn() as c:
      c.executescript(SCHEMA)
      for table, columns in ADDED_COLUMNS.items():  # a database from before they existed
        have = {r["name"] for r in c.execute(f"PRAGMA table_info({table})")}
        for name, kind in columns:
          if name not in have:
            c.execute(f"ALTER TABLE {table} ADD COLUMN {name} {kind}")
      for old, new in OLD_SOURCES.items():
        c.execute("UPDATE stats SET source = ? WHERE source = ?", (new, old))

  @contextlib.contextmanager
  def _conn(self) -> Iterator[sqlite3.Connection]:
    c = sqlite3.connect(self.path, timeout=30.0)
    try:
      _write_ahead_log(c)
      c.execute("PRAGMA busy_timeout=30000")
      c.row_factory = sqlite3.Row
      with c:
        yield c
    finally:
      c.close()

  # --- writing ----------------------------------------------------------------------------
  def start(self, run_id: str, task: str, algo: str, preset: str, seed: int, config: dict,
            out_dir: str, total_steps: int, resume_step: int | None = None) -> None:
    """Inserts a run, or marks a resumed one running again; statistics rows past the step it resumes
    from are dropped (they will be logged again), so no step is recorded twice."""
    with self._conn() as c:
      row = c.execute("SELECT status FROM experiments WHERE run_id = ?", (run_id,)).fetchone()
      if row and row["status"] == "running":  # its last process died without closing the run
        self._event(c, run_id, "crashed", None, "found on resume")
      if row:
        c.execute("UPDATE experiments SET status='running', pid=?, host=?, ended=NULL, total_steps=? "
                  "WHERE run_id=?", (os.getpid(), socket.gethostname(), total_steps, run_id))
        c.execute("DELETE FROM stats WHERE run_id=? AND step>?", (run_id, resume_step or 0))
      else:
        c.execute("INSERT INTO experiments (run_id, task, algo, preset, seed, config_json, status, "
                  "started, out_dir, pid, host, total_steps) VALUES (?,?,?,?,?,?,?,?,?,?,?,?)",
                  (run_id, task, algo, preset, seed, json.dumps(config), "running", utc_now(),
                   os.path.abspath(out_dir), os.getpid(), socket.gethostname(), total_steps))
      self._event(c, run_id, "resumed" if row else "started", resume_step or 0)

  def _event(self, c: sqlite3.Connection, run_id: str, event: str, step: int | None, detail: str = "") -> None:
    if event not in EVENTS:
      raise ValueError(f"unknown event {event!r}; known: {EVENTS}")
    c.execute("INSERT INTO events (run_id, event, step, time, detail) VALUES (?,?,?,?,?)",
              (run_id, event, step, utc_now(), detail))

  def wall_offset(self, run_id: str, step: int) -> float:
    """Training wall time (s) already spent up to a step (what a resumed run adds to)."""
    with self._conn() as c:
      r = c.execute("SELECT MAX(wall_s) FROM stats WHERE run_id=? AND step<=?", (run_id, step)).fetchone()
    return float(r[0] or 0.0)

  def log_stats(self, run_id: str, row: dict[str, Any], metrics: dict[str, float]) -> None:
    vals = [row.get(k) for k in STAT_COLUMNS]
    with self._conn() as c:
      c.execute(f"INSERT INTO stats (run_id, {', '.join(STAT_COLUMNS)}, metrics_json) "
                f"VALUES (?, {', '.join('?' * len(STAT_COLUMNS))}, ?)",
                [run_id, *vals, json.dumps(metrics)])

  def compiled(self, run_id: str, step: int, seconds: float) -> None:
    """Records that the run's training step compiled (at `step`: 0, or the step resumed from) in `seconds`."""
    with self._conn() as c:
      self._event(c, run_id, "compiled", step, f"{seconds:.3f}")

  def set_checkpoint(self, run_id: str, checkpoint_dir: str, step: int) -> None:
    with self._conn() as c:
      c.execute("UPDATE experiments SET checkpoint_dir=? WHERE run_id=?", (checkpoint_dir, run_id))
      self._event(c, run_id, "checkpoint", step)

  def finish(self, run_id: str, status: str, final: dict | None = None, step: int | None = None,
             detail: str = "") -> None:
    with self._conn() as c:
      c.execute("UPDATE experiments SET status=?, ended=?, final_json=? WHERE run_id=?",
                (status, utc_now(), json.dumps(final or {}), run_id))
      self._event(c, run_id, STATUS_EVENT[status], step, detail)

  def log_evals(self, run_id: str, trials: list[dict[str, Any]],
                replace: tuple[str, int | None] | None = None) -> None:
    """Adds one row per trial; replace=(scene, budget) first drops that scene's earlier rows."""
    with self._conn() as c:
      if replace is not None:
        c.execute("DELETE FROM evals WHERE run_id=? AND scene=? AND budget IS ?", (run_id, *replace))
      c.executemany(f"INSERT INTO evals (run_id, {', '.join(EVAL_COLUMNS)}, created) "
                    f"VALUES (?, {', '.join('?' * len(EVAL_COLUMNS))}, ?)",
                    [[run_id, *[t.get(k) for k in EVAL_COLUMNS], utc_now()] for t in trials])

  def log_attempt(self, study: str, cell: str, attempt: int, record: dict[str, Any], run_id: str | None) -> None:
    """A study's attempt at one of its runs (train.study): when, where, how it ended."""
    with self._conn() as c:
      c.execute("INSERT OR REPLACE INTO attempts VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
                (study, cell, attempt, run_id, record.get("worker"), record.get("started"), record.get("ended"),
                 record.get("rc"), record.get("phase"), int(bool(record.get("resumed"))), record.get("error")))

  def attempts(self, study: str) -> list[dict[str, Any]]:
    with self._conn() as c:
      return [dict(r) for r in c.execute("SELECT * FROM attempts WHERE study=? ORDER BY cell, attempt", (study,))]

  def add_launch(self, kind: str, spec: dict, out_dir: str | None) -> int:
    """Queues a launch (kind: run | resume | evaluate); returns its id."""
    with self._conn() as c:
      cur = c.execute("INSERT INTO launches (kind, spec_json, status, out_dir, created) VALUES (?, ?, 'queued', ?, ?)",
                      (kind, json.dumps(spec), out_dir, utc_now()))
      return int(cur.lastrowid)

  def set_launch(self, launch_id: int, **fields) -> None:
    """Updates a launch's status, started, ended, rc, error or out_dir."""
    allowed = {"kind", "status", "started", "ended", "rc", "error", "out_dir"}
    if not fields or not set(fields) <= allowed:
      raise ValueError(f"launch fields are {sorted(allowed)}, got {sorted(fields)}")
    with self._conn() as c:
      c.execute(f"UPDATE launches SET {', '.join(f'{k}=?' for k in fields)} WHERE id=?", (*fields.values(), launch_id))

  def launch(self, launch_id: int) -> dict[str, Any]:
    for launch in self.launches():
      if launch["id"] == launch_id:
        return launch
    raise KeyError(f"no launch {launch_id} in {self.path}")

  def launches(self, status: str | None = None) -> list[dict[str, Any]]:
    """Launches, oldest first, with their spec parsed; only those of one status if given."""
    with self._conn() as c:
      rows = [dict(r) for r in c.execute("SELECT * FROM launches ORDER BY id")]
    for r in rows:
      r["spec"] = json.loads(r.pop("spec_json"))
    return [r for r in rows if status is None or r["status"] == status]

  def import_runs(self, src: str, out_dir: str | None = None, only: list[str] | None = None) -> list[str]:
    """Copies every run of another database file (e.g. one that came back from a study's worker),
    or those whose ids are in `only`, into this one, replacing the rows of the same run ids;
    out_dir, if given, becomes their run folder. Returns the run ids."""
    tables = ("experiments", "stats", "events", "evals")
    with self._conn() as c:
      c.execute("ATTACH DATABASE ? AS src", (src,))
      ids = [r[0] for r in c.execute("SELECT run_id FROM src.experiments") if only is None or r[0] in only]
      marks = ", ".join("?" * len(ids))
      for table in reversed(tables):
        c.executemany(f"DELETE FROM {table} WHERE run_id=?", [(i,) for i in ids])
      for table in tables:
        mine = {r["name"] for r in c.execute(f"PRAGMA main.table_info({table})")}
        cols = ", ".join(r["name"] for r in c.execute(f"PRAGMA src.table_info({table})") if r["name"] in mine)
        c.execute(f"INSERT INTO main.{table} ({cols}) SELECT {cols} FROM src.{table} WHERE run_id IN ({marks})", ids)
      if out_dir is not None:
        c.executemany("UPDATE experiments SET out_dir=? WHERE run_id=?", [(os.path.abspath(out_dir), i) for i in ids])
    return ids

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

  def summaries(self) -> list[dict[str, Any]]:
    """Every run (as runs()) with its latest training statistics: step, steps_per_s, eps,
    return_mean, success_rate (one query, for run lists)."""
    latest = ("SELECT s.run_id, s.step, s.steps_per_s, s.eps, s.return_mean, s.success_rate FROM stats s "
              "JOIN (SELECT run_id, MAX(rowid) AS last FROM stats WHERE source='train' GROUP BY run_id) m "
              "ON s.rowid = m.last")
    with self._conn() as c:
      rows = {r["run_id"]: dict(r) for r in c.execute(latest)}
    empty = {"step": None, "steps_per_s": None, "eps": None, "return_mean": None, "success_rate": None}
    return [{**r, **{k: v for k, v in rows.get(r["run_id"], empty).items() if k != "run_id"}} for r in self.runs()]

  def run(self, run_id: str) -> dict[str, Any]:
    for r in self.runs():
      if r["run_id"] == run_id:
        return r
    raise KeyError(f"no run {run_id!r} in {self.path}")

  def stats(self, run_id: str) -> list[dict[str, Any]]:
    with self._conn() as c:
      return [dict(r) for r in c.execute("SELECT * FROM stats WHERE run_id=? ORDER BY step", (run_id,))]

  def events(self, run_id: str) -> list[dict[str, Any]]:
    with self._conn() as c:
      return [dict(r) for r in c.execute("SELECT event, step, time, detail FROM events WHERE run_id=? "
                                         "ORDER BY rowid", (run_id,))]

  def evals(self, run_id: str) -> list[dict[str, Any]]:
    with self._conn() as c:
      return [dict(r) for r in c.execute("SELECT * FROM evals WHERE run_id=? ORDER BY budget, scene, trial",
                                         (run_id,))]


  def eval_groups(self, run_id: str) -> dict[tuple[str, int | None], list[dict[str, Any]]]:
    """Its evaluation trials by (scene, budget): the final policy's (budget None) first, then by
    budget; scenes by name."""
    groups: dict[tuple[str, int | None], list[dict[str, Any]]] = {}
    for e in self.evals(run_id):
      groups.setdefault((e["scene"], e["budget"]), []).append(e)
    return groups


class NullDB:
  """The records of a run's other processes under jax.distributed: process 0 keeps them."""

  def start(self, *args, **kwargs) -> None: ...
  def finish(self, *args, **kwargs) -> None: ...
  def set_checkpoint(self, *args, **kwargs) -> None: ...
  def compiled(self, *args, **kwargs) -> None: ...
  def log_stats(self, *args, **kwargs) -> None: ...

  def wall_offset(self, run_id: str, step: int) -> float:
    return 0.0


def default_path(out_root: str = DEFAULT_ROOT) -> str:
  return os.path.join(out_root, DEFAULT_NAME)


def resolve_run(arg: str) -> str:
  """A run id, or a run directory (its run.json names the run)."""
  from train.core.run_record import is_run_dir, read_run_record  # noqa: PLC0415
  return read_run_record(arg)["run_id"] if is_run_dir(arg) else arg


def _list(db: ExperimentDB) -> None:
  print(f"{'run':52s} {'task':12s} {'algo':4s} {'status':13s} {'started':25s} {'steps':>10s} {'return':>7s}  directory")
  for r in db.runs():
    final = json.loads(r["final_json"] or "{}")
    ret = final.get("return_mean")
    print(f"{r['run_id']:52s} {r['task']:12s} {r['algo']:4s} {r['status']:13s} {r['started']:25s} "
          f"{final.get('step', '-')!s:>10s} {('-' if ret is None else f'{ret:.3f}'):>7s}  {r['out_dir']}")


def _show(db: ExperimentDB, run: dict) -> None:
  print(json.dumps({k: v for k, v in run.items() if k != "config_json"}, indent=1))
  for e in db.events(run["run_id"]):
    print(f"event {e['time']} {e['event']:11s} step {e['step'] if e['step'] is not None else '-'} {e['detail'] or ''}")
  stats = db.stats(run["run_id"])
  if stats:
    print("last statistics:", json.dumps({k: stats[-1][k] for k in STAT_COLUMNS}))
  for (scene, budget), trials in db.eval_groups(run["run_id"]).items():
    mean = lambda k: float(np.mean([t[k] if t.get(k) is not None else np.nan for t in trials]))  # nan: not recorded
    at = f" @ {budget:,} steps" if budget else ""
    print(f"eval {scene}{at}: {len(trials)} trials, progress {mean('progress'):.3f}, "
          f"success {mean('success'):.2f}, tipped {mean('tipped_over'):.2f}, collided {mean('collided'):.2f}")


def _export(db: ExperimentDB, run_id: str, path: str | None) -> None:
  out = open(path, "w", newline="") if path else sys.stdout
  w = csv.writer(out)
  w.writerow(STAT_COLUMNS)
  for r in db.stats(run_id):
    w.writerow([r[k] for k in STAT_COLUMNS])
  if path:
    out.close()


def main(argv: list[str] | None = None) -> int:
  p = argparse.ArgumentParser(prog="python -m train.db", description=__doc__.splitlines()[0])
  p.add_argument("--db", default=default_path(), help=f"SQLite file (default {default_path()})")
  sub = p.add_subparsers(dest="cmd", required=True)
  sub.add_parser("list", help="one line per experiment")
  s = sub.add_parser("show", help="an experiment's row, events, last statistics and evaluations")
  s.add_argument("run", help="run id or run directory")
  e = sub.add_parser("export", help="an experiment's training statistics")
  e.add_argument("run", help="run id or run directory")
  e.add_argument("--csv", action="store_true", required=True)
  e.add_argument("--out", help="file (default: standard output)")
  args = p.parse_args(argv)
  if not os.path.exists(args.db):
    print(f"error: no database at {args.db}", file=sys.stderr)
    return 2
  db = ExperimentDB(args.db)
  if args.cmd == "list":
    _list(db)
    return 0
  try:
    run = db.run(resolve_run(args.run))
  except KeyError as err:
    print(f"error: {err.args[0]}", file=sys.stderr)
    return 2
  if args.cmd == "show":
    _show(db, run)
  else:
    _export(db, run["run_id"], args.out)
  return 0


def _main() -> int:
  """main, quiet when its reader goes away (`python -m train.db export RUN --csv | head`)."""
  try:
    return main()
  except BrokenPipeError:
    os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # no second error at exit's flush
    return 0


if __name__ == "__main__":
  sys.exit(_main())

"""`python -m train.study timeline NAME [--root studies]`: when each program of a study ran, read from
its folder (state.json: which runs trained together in one program) and its database (each attempt's
run; each run's `compiled` and end-of-training events): per program its runs, its worker, and the
seconds from the study's first start to the program's start, to its training step compiled, to its
training ended (its last run's) and to its attempt ended (evaluations included); then where its
longest run's clock went (its first run to report the most steps; one stopped early says little):
seconds of training (the steps between two reports over their steps/s, which leave evaluations and
checkpoints out) and seconds besides (paused), which add up to its clock at its last report."""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import os
import sys

from train.db import STATUS_EVENT, TRAIN_SOURCE, read_only
from train.study.executor import STUDY_DB, folder_parser, no_study, read_cells

TRAINING_ENDS = frozenset(STATUS_EVENT.values())  # the events a training session ends with


@dataclasses.dataclass(frozen=True)
class Program:
  """One attempt of one run, or of a pack of runs trained as one program; times in s since the epoch
  (None: not recorded: `compiled` before 2026-11-29, an attempt that has not ended, or the run events
  of an attempt still running, which the study's database links to it only once it ends);
  stopped: the study's own stop ended it."""
  cells: tuple[str, ...]
  worker: str | None
  started: float
  compiled: float | None
  trained: float | None
  ended: float | None
  stopped: bool = False
  # its longest run's (training s, paused s): run_clock (a resumed run's: its whole clock)
  clock: tuple[float, float] | None = None


def _epoch(iso: str) -> float:
  return datetime.datetime.fromisoformat(iso).timestamp()


def _attempts(folder: str) -> dict[tuple, list[tuple[str, int, dict]]]:
  """state.json's attempts grouped by program -> [(cell id, attempt number from 1, attempt record)].
  A program is a cell's attempt, or the k-th attempt of a pack (its cells' attempts that list the
  same pack for the k-th time)."""
  grouped: dict = {}
  for cid, cell in read_cells(folder).items():
    seen: dict[tuple, int] = {}
    for number, attempt in enumerate(cell["attempts"], start=1):
      pack = tuple(attempt.get("pack") or (cid, number))
      seen[pack] = seen.get(pack, 0) + 1
      grouped.setdefault((pack, seen[pack]), []).append((cid, number, attempt))
  return grouped


def _database(db: str) -> tuple[dict[tuple[str, int], str], dict[str, list[tuple[str, float]]], dict[str, list]]:
  """({(cell, attempt number): run id}, {run id: [(event, time s)]}, {run id: its training reports
  [(step, wall s, steps/s)] in step order}) of the study's database."""
  with read_only(db) as c:
    runs = {(cell, n): run_id for cell, n, run_id in c.execute("SELECT cell, attempt, run_id FROM attempts")}
    events: dict = {}
    for run_id, event, time in c.execute("SELECT run_id, event, time FROM events ORDER BY rowid"):
      events.setdefault(run_id, []).append((event, _epoch(time)))
    reports: dict = {}
    for run_id, step, wall, rate in c.execute("SELECT run_id, step, wall_s, steps_per_s FROM stats WHERE source = ? "
                                              "ORDER BY run_id, step", (TRAIN_SOURCE,)):
      reports.setdefault(run_id, []).append((step, wall, rate))
  return runs, events, reports


def run_clock(reports: list[tuple[int, float, float | None]]) -> tuple[float, float] | None:
  """(training s, paused s) of a run's clock at its last training report (reports: [(step, wall s,
  steps/s)] in step order, from step 0 and wall 0): the steps between two reports over the later
  one's steps/s, and the rest of its wall time; None without reports or where one has no rate."""
  if not reports or any(rate is None or rate <= 0 for _, _, rate in reports):
    return None
  training, step = 0.0, 0
  for later, _, rate in reports:
    training, step = training + (later - step) / rate, later
  return training, reports[-1][1] - training


def _program(members: list[tuple[str, int, dict]], runs: dict, events: dict, reports: dict) -> Program:
  attempts = [a for _, _, a in members]
  start, ends = min(a["started"] for a in attempts), [a.get("ended") for a in attempts]
  end = None if None in ends else max(ends)
  # this attempt's events (a resumed run's database holds its earlier attempts' too; times to the second)
  mine = [(e, t) for cid, n, _ in members for e, t in events.get(runs.get((cid, n)), ())
          if t >= int(start) and (end is None or t <= end + 1)]
  compiled = [t for e, t in mine if e == "compiled"]
  trained = [t for e, t in mine if e in TRAINING_ENDS]
  # the first of the runs whose last report is at the most steps: the program's whole training (the
  # reports of runs that end together differ by their logging order, so their wall times do not choose)
  last_steps = [reports.get(runs.get((cid, n)), [(0, 0.0, None)])[-1][0] for cid, n, _ in members]
  longest = runs.get(members[last_steps.index(max(last_steps))][:2])
  return Program(tuple(cid for cid, _, _ in members), attempts[0].get("worker"), start,
                 min(compiled) if compiled else None, max(trained) if trained else None, end,
                 any(a.get("stopped") for a in attempts), run_clock(reports.get(longest, [])))


def programs(folder: str) -> list[Program]:
  """Every attempt of the study's runs, a pack's as one program, in the order they started.
  FileNotFoundError where the folder holds no study (state.json). A study whose first attempt has not
  ended has no database yet: its programs' starts only."""
  db = os.path.join(folder, STUDY_DB)
  grouped = _attempts(folder)
  runs, events, reports = _database(db) if os.path.exists(db) else ({}, {}, {})
  return sorted((_program(m, runs, events, reports) for m in grouped.values()), key=lambda p: (p.started, p.cells))


def lines(name: str, progs: list[Program]) -> list[str]:
  """What `timeline` prints: the study's span, then one line per program (s since its first start;
  then its longest run's clock: training s, paused s)."""
  if not progs:
    return [f"study {name}: no attempt has started"]
  t0 = min(p.started for p in progs)
  ends = [p.ended for p in progs if p.ended is not None]
  running = sum(p.ended is None and not p.stopped for p in progs)
  span = f"{max(ends) - t0:,.0f} s from its first start to its last end" if ends else "no attempt has ended"
  span += f", {running} programs not ended" if running else ""
  out = [f"study {name}: {span}; {len(progs)} programs of {len({c for p in progs for c in p.cells})} runs "
         f"(s from the first start; -: not recorded)",
         f"{'program (its first run, + the others)':<48} {'runs':>4}  {'worker':<8} {'start':>7} {'compiled':>9} "
         f"{'trained':>8} {'ended':>7} {'training':>9} {'paused':>7}"]
  at = lambda t: "-" if t is None else f"{t - t0:,.0f}"  # noqa: E731
  for p in progs:
    first = p.cells[0] + (f" +{len(p.cells) - 1}" if len(p.cells) > 1 else "")
    ended = "stopped" if p.stopped and p.ended is None else at(p.ended)
    training, paused = ("-", "-") if p.clock is None else (f"{s:,.0f}" for s in p.clock)
    out.append(f"{first:<48} {len(p.cells):>4}  {str(p.worker or '-'):<8} {at(p.started):>7} {at(p.compiled):>9} "
               f"{at(p.trained):>8} {ended:>7} {training:>9} {paused:>7}")
  return out


def main(argv: list[str]) -> int:
  args = folder_parser("timeline", __doc__).parse_args(argv)
  folder = os.path.join(args.root, args.name)
  try:
    print("\n".join(lines(args.name, programs(folder))))
  except FileNotFoundError as e:
    return no_study(folder, args.name, e.filename)
  return 0

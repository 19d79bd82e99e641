"""For each run of a study: an upper bound on the time from its attempt's start to its first probe
with success >= a threshold, from the study's database (STUDY/study.sqlite: the attempts, and each
run's rows and events, imported from its run.sqlite when it came back; the run's id from its
RUN/run.json). The attempt's start is stamped when the study hands the run to a worker, so
the bound includes any wait for a slot and the process's start-up and compilation (for packed
seeds: the program of all of them). A probe row's wall_s counts from the run's reporter start; that
start is at most the run's latest 'finished' event time (stored rounded down to the second, hence
+1 s) less its last row's wall_s, since the run ends after its last row. The study's and the
worker's clocks are assumed the same (one host). A run without a 'finished' event gets no bound.

python scripts/analysis/time_to_probe_success.py results/studies/nav [--threshold 0.9]
"""

from __future__ import annotations

import argparse
import datetime
import os
import sqlite3

from train.core.run_record import run_id_in
from train.db import read_only
from train.study.executor import STUDY_DB, cell_folder_of


def run_bound(c: sqlite3.Connection, run_id: str, attempt_start: float, threshold: float) -> tuple[int, float] | None:
  """(step, seconds) of run run_id's first probe >= threshold, seconds bounded from above; None if
  it has none or did not finish (no bound)."""
  probes = c.execute("SELECT step, wall_s FROM stats WHERE run_id = ? AND source = 'probe' AND success_rate >= ? "
                     "ORDER BY step LIMIT 1", (run_id, threshold)).fetchall()
  last_wall = c.execute("SELECT max(wall_s) FROM stats WHERE run_id = ?", (run_id,)).fetchone()[0]
  finished = c.execute("SELECT time FROM events WHERE run_id = ? AND event = 'finished' ORDER BY time DESC LIMIT 1",
                       (run_id,)).fetchone()
  if not probes or finished is None:
    return None
  finished_at_most = datetime.datetime.fromisoformat(finished[0]).timestamp() + 1.0  # s: stored rounded down
  reporter_start_at_most = finished_at_most - last_wall
  step, wall = probes[0]
  return step, reporter_start_at_most + wall - attempt_start


def main(argv=None) -> int:
  p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  p.add_argument("study", help="a study folder (study.sqlite, runs/*/run.json)")
  p.add_argument("--threshold", type=float, default=0.9, help="probe success (default %(default)s)")
  args = p.parse_args(argv)
  with read_only(os.path.join(args.study, STUDY_DB)) as c:
    starts = dict(c.execute("SELECT cell, min(started) FROM attempts GROUP BY cell"))
    for cell, start in sorted(starts.items()):
      run_id = run_id_in(cell_folder_of(args.study, cell))
      if run_id is None or c.execute("SELECT 1 FROM stats WHERE run_id = ? LIMIT 1", (run_id,)).fetchone() is None:
        continue  # no run record, or a run that never trained (a baseline)
      found = run_bound(c, run_id, start, args.threshold)
      print(f"{cell}: " + (f"probe success >= {args.threshold} at step {found[0]:,}, at most {found[1]:.0f} s "
                           "after the attempt's start" if found else f"no probe >= {args.threshold}, or not finished (no bound)"))
  return 0


if __name__ == "__main__":
  raise SystemExit(main())

"""For each run of a study: an upper bound on the time from its attempt's start (the process that
trained it; for packed seeds, the program of all of them) to its first probe with success >= a
threshold, from the records that came back (STUDY/study.sqlite's attempts, each run's
RUN/run.sqlite). A probe row's wall_s counts from the run's reporter start, which comes after
start-up and compilation; that start is at most the run's 'finished' event time less its last
row's wall_s (the run ends after its last row), so the bound adds that to the probe's wall_s.

python scripts/analysis/time_to_probe_success.py results/studies/nav [--threshold 0.9]
"""

from __future__ import annotations

import argparse
import datetime
import os
import sqlite3

from train.study.executor import cell_folder_of


def run_bound(run_db: str, attempt_start: float, threshold: float) -> tuple[int, float] | None:
  """(step, seconds) of the run's first probe >= threshold, seconds bounded from above; None if none."""
  with sqlite3.connect(run_db) as c:
    probes = c.execute("SELECT step, wall_s FROM stats WHERE source = 'probe' AND success_rate >= ? "
                       "ORDER BY step LIMIT 1", (threshold,)).fetchall()
    last_wall = c.execute("SELECT max(wall_s) FROM stats").fetchone()[0]
    finished = c.execute("SELECT time FROM events WHERE event = 'finished'").fetchone()
  if not probes or finished is None:
    return None
  reporter_start_at_most = datetime.datetime.fromisoformat(finished[0]).timestamp() - last_wall
  step, wall = probes[0]
  return step, reporter_start_at_most + wall - attempt_start


def main(argv=None) -> int:
  p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  p.add_argument("study", help="a study folder (study.sqlite, runs/*/run.sqlite)")
  p.add_argument("--threshold", type=float, default=0.9, help="probe success (default %(default)s)")
  args = p.parse_args(argv)
  with sqlite3.connect(os.path.join(args.study, "study.sqlite")) as c:
    starts = dict(c.execute("SELECT cell, min(started) FROM attempts GROUP BY cell"))
  for cell, start in sorted(starts.items()):
    run_db = os.path.join(cell_folder_of(args.study, cell), "run.sqlite")
    if not os.path.exists(run_db):
      continue
    found = run_bound(run_db, start, args.threshold)
    print(f"{cell}: " + (f"probe success >= {args.threshold} at step {found[0]:,}, at most {found[1]:.0f} s "
                         "after the attempt's start" if found else f"no probe >= {args.threshold}"))
  return 0


if __name__ == "__main__":
  raise SystemExit(main())

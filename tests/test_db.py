"""The experiment database opened by many processes at once."""

import json
import os
import subprocess
import sys

ROUNDS, PROCESSES = 40, 8  # new files, processes opening each at the same instant (before the fix:
#                            about 1 opening in 40 failed, i.e. ~8 of these 320)


def test_processes_opening_one_new_database_together_all_get_it(tmp_path):
  """Switching a new file to WAL mode answered "database is locked" without waiting while another
  process opened it: evaluations started together on one new database crashed."""
  script = os.path.join(os.path.dirname(os.path.abspath(__file__)), "db_race.py")
  done = subprocess.run([sys.executable, script, str(tmp_path), str(ROUNDS), str(PROCESSES)], capture_output=True,
                        text=True, timeout=300)
  assert done.returncode == 0, done.stderr[-2000:]
  got = json.loads(done.stdout)
  assert got["failed"] == [] and got["runs_in_first"] == PROCESSES

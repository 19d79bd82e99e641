"""Processes opening new experiment databases together, forked from this small process (forking
a pytest worker that holds compiled JAX programs costs ~0.1 s a process): prints, as JSON, what
each opening that failed raised, and how many runs the first database holds.

    python tests/db_race.py FOLDER ROUNDS PROCESSES
"""

import json
import multiprocessing
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from train.db import ExperimentDB  # noqa: E402  (imported once, before the processes fork)


def _open(path, run_id, barrier, results):
  try:
    barrier.wait(timeout=60)
    ExperimentDB(path).start(run_id, "asc-inc-cog", "ppo", "cpu", 0, {}, "/x", 1)
    results.put("ok")
  except Exception as e:  # noqa: BLE001  (reported, not raised, so that the parent counts it)
    results.put(repr(e))


def main(folder: str, rounds: int, processes: int) -> dict:
  ctx = multiprocessing.get_context("fork")
  failed = []
  for i in range(rounds):
    barrier, results = ctx.Barrier(processes), ctx.Queue()
    procs = [ctx.Process(target=_open, args=(os.path.join(folder, f"db{i}.sqlite"), f"r{k}", barrier, results),
                         daemon=True) for k in range(processes)]
    try:
      for p in procs:
        p.start()
      failed += [r for r in (results.get(timeout=120) for _ in procs) if r != "ok"]
    finally:
      for p in procs:
        p.join(timeout=10)
        if p.is_alive():
          p.terminate()
  return {"failed": failed, "runs_in_first": len(ExperimentDB(os.path.join(folder, "db0.sqlite")).runs())}


if __name__ == "__main__":
  print(json.dumps(main(sys.argv[1], int(sys.argv[2]), int(sys.argv[3]))))

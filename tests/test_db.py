"""The experiment database opened by many processes at once."""

import multiprocessing

ROUNDS, PROCESSES = 40, 8  # new files, processes opening each at the same instant (before the fix:
#                            about 1 opening in 40 failed, i.e. ~8 of these 320)


def _open(path, run_id, barrier, results):
  from train.db import ExperimentDB
  barrier.wait()
  try:
    ExperimentDB(path).start(run_id, "asc-inc-cog", "ppo", "cpu", 0, {}, "/x", 1)
    results.put("ok")
  except Exception as e:  # noqa: BLE001  (reported, not raised, so that the parent counts it)
    results.put(repr(e))


def test_processes_opening_one_new_database_together_all_get_it(tmp_path):
  """Switching a new file to WAL mode answered "database is locked" without waiting while another
  process opened it: evaluations started together on one new database crashed."""
  import train.db  # noqa: F401  (imported once, before the processes fork)
  ctx = multiprocessing.get_context("fork")
  failed = []
  for i in range(ROUNDS):
    barrier, results = ctx.Barrier(PROCESSES), ctx.Queue()
    procs = [ctx.Process(target=_open, args=(str(tmp_path / f"db{i}.sqlite"), f"r{k}", barrier, results))
             for k in range(PROCESSES)]
    for p in procs:
      p.start()
    failed += [r for r in (results.get(timeout=120) for _ in procs) if r != "ok"]
    for p in procs:
      p.join()
  assert failed == []
  from train.db import ExperimentDB
  assert len(ExperimentDB(str(tmp_path / "db0.sqlite")).runs()) == PROCESSES  # every run recorded

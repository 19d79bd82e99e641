"""A pack's evaluations (train.study.worker): one process per run, at most so many at a time, each
run's exit code and output kept."""

import os

from train.study import worker

STAND_IN = """import sys, time
run = sys.argv[1]
open(run + "/span", "w").write(f"{time.time()} ")
time.sleep(0.4)
open(run + "/span", "a").write(f"{time.time()}")
print("evaluated", run)
sys.exit(3 if run.endswith("bad") else 0)
"""


def test_a_packs_evaluations_run_at_most_so_many_at_once_and_each_keeps_its_exit_code_and_output(tmp_path):
  script = tmp_path / "evaluate_stand_in.py"
  script.write_text(STAND_IN)
  names = ["a", "b", "c", "d", "bad"]
  folders = {m: str(tmp_path / m) for m in names}
  for folder in folders.values():
    os.makedirs(folder)
  done = worker._evaluate_side_by_side(folders, ["--suite"], (str(script),), str(tmp_path), at_once=2)
  assert {m: code for m, (_, code, _) in done.items()} == {"a": 0, "b": 0, "c": 0, "d": 0, "bad": 3}
  assert all(f"evaluated {folders[m]}" in out for m, (_, _, out) in done.items())
  spans = [tuple(map(float, open(os.path.join(f, "span")).read().split())) for f in folders.values()]
  most = max(sum(1 for s, e in spans if s <= t < e) for t, _ in spans)  # processes running at each start
  assert most == 2  # two at once, never more: five of 0.4 s each take three rounds
  assert worker.evaluations_at_once() >= 1

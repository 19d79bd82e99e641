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


def test_runs_of_one_configuration_are_evaluated_after_the_first_of_them_which_compiles_alone(tmp_path):
  import json
  script = tmp_path / "evaluate_stand_in.py"
  script.write_text(STAND_IN)
  configs = {"up0": "up", "up1": "up", "up2": "up", "down0": "down", "down1": "down", "plain": None}
  folders = {m: str(tmp_path / m) for m in configs}
  for m, task in configs.items():
    os.makedirs(folders[m])
    if task:  # seeds apart, one configuration per task
      json.dump({"config": {"task": task}, "algo": "sac", "preset": "paper", "hp": [], "library": "mjx-tracks",
                 "seed": int(m[-1])}, open(os.path.join(folders[m], "run.json"), "w"))
  assert worker.compile_leads(folders) == {"up0": None, "up1": "up0", "up2": "up0", "down0": None,
                                           "down1": "down0", "plain": None}
  done = worker._evaluate_side_by_side(folders, ["--suite"], (str(script),), str(tmp_path), at_once=6)
  assert all(code == 0 for _, code, _ in done.values())
  span = {m: tuple(map(float, open(os.path.join(f, "span")).read().split())) for m, f in folders.items()}
  for m, lead in worker.compile_leads(folders).items():
    if lead is not None:
      assert span[m][0] >= span[lead][1]  # started once its lead had ended
  assert span["down0"][0] < span["up0"][1] and span["plain"][0] < span["up0"][1]  # the leads side by side

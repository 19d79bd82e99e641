"""A study on a local Dask cluster of 2 worker processes, each with its own scratch folder (no
shared filesystem), with a stand-in for train.run (tests/fake_study_run.py): a crashed run is
retried from the checkpoint that came back, a run whose worker is killed is retried, every
attempt is recorded, and a study started again runs nothing finished."""

import json
import os
import pathlib
import signal
import threading
import time

from distributed import Client, Nanny

from train.study.cluster import local_cluster
from train.study.executor import StudyRunner, cell_folder
from train.study.spec import cells, study_from_dict
from train.study.status import summary

FAKE = str(pathlib.Path(__file__).with_name("fake_study_run.py"))
COMMANDS = ((FAKE, "train"), (FAKE, "evaluate"))  # after the worker's Python
STUDY = {"name": "t", "tasks": ["asc-inc-cog", "asc-uni-cog"], "seeds": [0, 1], "retries": 1, "eval_trials": 3,
         "groups": [{"name": "g", "algo": "ppo", "preset": "cpu", "steps": [400], "backend": "cpu"}]}
SLOW = "g/asc-inc-cog/400/s0"  # seed 0 runs slowly; its worker is killed during its first attempt


def _workers(tmp_path) -> dict:
  specs = {}
  for name in ("a", "b"):
    scratch = tmp_path / f"worker-{name}"
    scratch.mkdir()
    env = {"TMPDIR": str(scratch), "FAKE_SLOW_SEED": "0", "FAKE_CRASH_SEED": "1"}
    specs[name] = {"cls": Nanny, "options": {"nthreads": 1, "resources": {"cpu": 1}, "env": env,
                                              "local_directory": str(scratch)}}
  return specs


def _kill_the_worker_running(client, key: str, timeout_s: float = 60) -> None:
  t_end = time.time() + timeout_s
  while time.time() < t_end:
    for addr, keys in client.processing().items():
      if key in keys:
        time.sleep(0.5)  # let the run start
        os.kill(client.run(os.getpid, workers=[addr])[addr], signal.SIGKILL)
        return
    time.sleep(0.05)
  raise AssertionError(f"no worker ran {key}")


def test_crashes_and_killed_workers_are_retried_recorded_and_not_rerun(tmp_path):
  spec, folder = study_from_dict(STUDY), str(tmp_path / "study")
  with local_cluster(_workers(tmp_path)) as cluster, Client(cluster) as client:
    killer = threading.Thread(target=_kill_the_worker_running, args=(client, f"{SLOW}/attempt-1"))
    killer.start()
    counts = StudyRunner(spec, folder, client, COMMANDS, backends=("cpu",)).run()
    killer.join()
    assert counts == {"done": 4, "running": 0, "queued": 0, "failed": 0}
    state = json.load(open(os.path.join(folder, "state.json")))["cells"]
    slow = state[SLOW]["attempts"]
    assert len(slow) == 2 and "KilledWorker" in slow[0]["error"] and slow[1]["rc"] == 0
    for c in cells(spec):
      run = cell_folder(folder, c)
      assert os.path.exists(os.path.join(run, "eval-hardest.json")) and os.path.isdir(os.path.join(run, "checkpoints", "400"))
      if c.seed == 1:  # crashed after its first checkpoint, resumed from the folder that came back
        tries = state[c.id]["attempts"]
        assert [a["rc"] for a in tries] == [1, 0] and tries[1]["resumed"]
        assert json.load(open(os.path.join(run, "run.json")))["sessions"] == 2
    assert {a["worker"] for c in state.values() for a in c["attempts"] if a.get("worker")} == {"a", "b"}
    lines = summary(folder, runs=True)
    attempts, retried = sum(len(c["attempts"]) for c in state.values()), sum(len(c["attempts"]) > 1 for c in state.values())
    assert lines[0] == f"study study: 4 runs: 4 done, 0 failed, 0 not finished; {attempts} attempts, {retried} runs retried"
    assert attempts >= 7 and retried >= 3  # the killed run and the two crashed ones
    assert any(line.startswith(SLOW) and " done " in line and line.endswith("1.00") for line in lines[2:])
    again = StudyRunner(spec, folder, client, COMMANDS, backends=("cpu",)).run()
    assert again["done"] == 4 and json.load(open(os.path.join(folder, "state.json")))["cells"] == state


def test_the_default_cluster_pins_one_worker_per_gpu_and_counts_slots_as_resources():
  from train.study.cluster import worker_specs
  specs = worker_specs(["0", "3"], 2, 4)
  assert list(specs) == ["gpu0", "gpu3", "cpu"]
  assert specs["gpu3"]["options"]["env"]["CUDA_VISIBLE_DEVICES"] == "3"
  assert specs["gpu3"]["options"]["resources"] == {"gpu": 2} and specs["gpu3"]["options"]["nthreads"] == 2
  assert specs["cpu"]["options"]["env"]["JAX_PLATFORMS"] == "cpu" and specs["cpu"]["options"]["resources"] == {"cpu": 4}
  assert "cpu" not in worker_specs(["0"], 1, 0)

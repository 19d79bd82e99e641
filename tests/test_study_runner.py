"""A study on a local Dask cluster of 2 worker processes, each with its own scratch folder (the first
test: no shared filesystem, run folders come back as tars; the others: moved into the study's
folder), with a stand-in for train.run (tests/fake_study_run.py): a crashed run is
retried from the checkpoint that came back, a run whose worker is killed is retried, every
attempt is recorded, and a study started again runs nothing finished."""

import io
import json
import os
import pathlib
import shutil
import signal
import threading
import time

import pytest
import scipy.stats
from distributed import Client, Nanny
from fake_study_run import fake_success

from mjx_tracks.envs.config import ConfigError
from train.db import ExperimentDB

from train.study.cluster import local_cluster
from train.study.executor import STUDY_DB, StudyRunner, cell_folder, next_attempt, starts_afresh
from train.study.spec import cells, study_from_dict
from train.study.report import write_report
from train.study import timeline
from train.study.status import summary

FAKE = str(pathlib.Path(__file__).with_name("fake_study_run.py"))
COMMANDS = ((FAKE, "train"), (FAKE, "evaluate"))  # after the worker's Python
STUDY = {"name": "t", "tasks": ["asc-inc-cog", "asc-uni-cog"], "seeds": [0, 1], "retries": 1, "eval_trials": 4,
         "groups": [{"name": "g", "algo": "ppo", "preset": "cpu", "steps": [200, 400], "budgets": "milestones",
                     "backend": "cpu"}],
         "compare": [["asc-inc-cog", "asc-uni-cog"]], "baselines": ["full"]}
SLOW = "g/asc-inc-cog/400/s0"  # seed 0 runs slowly; its worker is killed during its first attempt


def _workers(tmp_path, slow: str = "0", **fake) -> dict:
  """Two workers of one CPU slot each; fake: more of the stand-in's FAKE_* settings."""
  specs = {}
  for name in ("a", "b"):
    scratch = tmp_path / f"worker-{name}"
    scratch.mkdir()
    env = {"TMPDIR": str(scratch), "FAKE_SLOW_SEED": slow, "FAKE_CRASH_SEED": "1", **fake}
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
    stream = io.StringIO()
    counts = StudyRunner(spec, folder, client, COMMANDS, backends=("cpu",), stream=stream, progress_every=0.5,
                         move_folders=False).run()  # as from workers on other machines: tars
    killer.join()
    assert not os.path.exists(os.path.join(folder, ".handoff"))
    returned = json.load(open(os.path.join(folder, "state.json")))["cells"]
    assert {a.get("returned") for c in returned.values() for a in c["attempts"] if a.get("returned")} == {"tar"}
    assert counts == {"done": 6, "running": 0, "queued": 0, "failed": 0}  # 4 trained runs, 2 baseline evaluations
    state = json.load(open(os.path.join(folder, "state.json")))["cells"]
    slow = state[SLOW]["attempts"]
    assert len(slow) == 2 and "KilledWorker" in slow[0]["error"] and slow[1]["rc"] == 0
    for c in cells(spec):
      run = cell_folder(folder, c)
      if c.is_baseline:  # evaluated only, once
        assert not os.path.exists(os.path.join(run, "checkpoints")) and state[c.id]["status"] == "done"
        assert not any(a["train"] for a in state[c.id]["attempts"])
        assert json.load(open(os.path.join(run, "run.json")))["run_id"] == f"{c.task}-baseline-full"
        continue
      assert os.path.exists(os.path.join(run, "eval-hardest.json")) and os.path.isdir(os.path.join(run, "checkpoints", "400"))
      if c.seed == 1:  # crashed after its first checkpoint, resumed from the folder that came back
        tries = state[c.id]["attempts"]
        assert [a["rc"] for a in tries] == [1, 0] and tries[1]["resumed"]
        assert json.load(open(os.path.join(run, "run.json")))["sessions"] == 2
    assert {a["worker"] for c in state.values() for a in c["attempts"] if a.get("worker")} == {"a", "b"}
    progress = stream.getvalue().splitlines()
    assert progress[-1].startswith("[study] t: 6 done, 0 running, 0 waiting, 0 to retry, 0 failed")
    assert len(progress) > 1 + sum(len(c["attempts"]) for c in state.values())  # lines while runs ran, too
    assert any(" 1 running" in line or " 2 running" in line for line in progress)
    assert all(int(line.split(" done, ")[1].split(" running")[0]) <= 2 for line in progress)  # 2 slots: no more run
    lines = summary(folder, runs=True)
    attempts, retried = sum(len(c["attempts"]) for c in state.values()), sum(len(c["attempts"]) > 1 for c in state.values())
    assert lines[0] == (f"study study: 6 runs: 6 done, 0 failed, 0 not finished (0 submitted: running or waiting for "
                        f"a slot); {attempts} attempts, {retried} runs retried")
    assert attempts >= 7 and retried >= 3  # the killed run and the two crashed ones
    assert any(line.startswith(SLOW) and " done " in line and line.endswith("1.00") for line in lines[2:])
    db_attempts = ExperimentDB(os.path.join(folder, STUDY_DB)).attempts(spec.name)
    assert [(a["cell"], a["rc"]) for a in db_attempts] == [(cid, a["rc"]) for cid in sorted(state) for a in state[cid]["attempts"]]
    assert all(a["run_id"] for a in db_attempts if a["rc"] is not None)  # every attempt that ran names its run
    again = StudyRunner(spec, folder, client, COMMANDS, backends=("cpu",)).run()
    assert again["done"] == 6 and json.load(open(os.path.join(folder, "state.json")))["cells"] == state
  _check_report(folder)


def _per_run_success(task: str, budget: int) -> list[float]:
  """Each seed's success rate as the stand-in records it (plain Python: the report's oracle)."""
  return [sum(fake_success(task, seed, budget, i) for i in range(4)) / 4 for seed in (0, 1)]


def _check_report(folder: str) -> None:
  """report.md holds rliable's IQM and probability of improvement of the recorded trials (checked
  against scipy's trimmed mean and the pairwise count) and links figures that exist."""
  path = write_report(folder, "python -m train.study report t")
  text = open(path).read()
  for task in ("asc-inc-cog", "asc-uni-cog"):
    for budget in (200, 400):
      iqm = scipy.stats.trim_mean(_per_run_success(task, budget), 0.25)
      row = [line for line in text.splitlines() if line.startswith(f"| g | {task} | {budget:,} | 2 |")]
      assert len(row) == 1 and row[0].split(" | ")[4].startswith(f"{iqm:.2f} ["), row
  for budget in (200, 400):
    a, b = _per_run_success("asc-inc-cog", budget), _per_run_success("asc-uni-cog", budget)
    p = sum((x > y) + 0.5 * (x == y) for x in a for y in b) / (len(a) * len(b))
    row = [line for line in text.splitlines() if line.startswith(f"| g | {budget:,} | asc-inc-cog | asc-uni-cog |")]
    assert len(row) == 1 and row[0].split(" | ")[4].startswith(f"{p:.2f} ["), row
  for task in ("asc-inc-cog", "asc-uni-cog"):  # the baseline's trials (seed 0's outcomes, budget 0) beside them
    full = sum(fake_success(task, 0, 0, i) for i in range(4)) / 4
    assert f"| {task} | baseline full | {full:.3f} | 0.500 | 0.200 | 0.100 |" in text
    assert f"| baseline-full | {task} | - | 1 | {full:.2f} [" in text
  figures = [line[line.index("(") + 1:-1] for line in text.splitlines() if line.startswith("![")]
  assert sorted(figures) == ["curves-g-step.png", "curves-g-wall_s.png", "final-g.png"]
  assert all(os.path.getsize(os.path.join(folder, f)) > 10_000 for f in figures)


def test_the_default_cluster_pins_one_worker_per_gpu_and_counts_slots_as_resources():
  from train.study.cluster import worker_specs
  specs = worker_specs(["0", "3"], 2, 4)
  assert list(specs) == ["gpu0", "gpu3", "cpu"]
  assert specs["gpu3"]["options"]["env"]["CUDA_VISIBLE_DEVICES"] == "3"
  assert specs["gpu3"]["options"]["resources"] == {"gpu": 2} and specs["gpu3"]["options"]["nthreads"] == 2
  assert specs["cpu"]["options"]["env"]["JAX_PLATFORMS"] == "cpu" and specs["cpu"]["options"]["resources"] == {"cpu": 4}
  assert "cpu" not in worker_specs(["0"], 1, 0)


class _RecordingClient:
  """Records what the runner submits (no cluster)."""

  def __init__(self):
    self.calls = []

  def submit(self, fn, *args, **kwargs):
    self.calls.append(args)


def test_a_run_whose_evaluation_failed_is_evaluated_again_even_after_a_stopped_attempt(tmp_path):
  """Its training finished, evaluating failed, and the study was stopped during the retry: the
  next start evaluates it again instead of training a finished run (which train.run refuses); so
  does any start once its checkpoints reach its total steps."""
  spec, folder = study_from_dict(STUDY), str(tmp_path / "study")
  cid = cells(spec)[0].id
  runner = StudyRunner(spec, folder, _RecordingClient(), COMMANDS, backends=("cpu",))
  os.makedirs(os.path.join(cell_folder(folder, cells(spec)[0]), "checkpoints", "400"))
  runner.state.cells[cid]["attempts"] = [
      {"started": 1.0, "ended": 2.0, "rc": 2, "phase": "evaluate"},
      {"started": 3.0, "ended": None, "rc": None, "phase": None, "stopped": True}]
  runner._submit(cid)
  _, _, resume, train, _, handoff = runner.client.calls[-1]
  assert handoff.shared()  # a worker here moves the folder into the study's
  assert resume is not None and train is False
  runner.state.cells[cid]["attempts"][0]["phase"] = "train"  # training itself failed: train again
  runner._submit(cid)
  assert runner.client.calls[-1][3] is True
  json.dump({"total_steps": 400}, open(os.path.join(cell_folder(folder, cells(spec)[0]), "run.json"), "w"))
  runner._submit(cid)  # ... unless its checkpoints reach its total steps
  assert runner.client.calls[-1][3] is False


_STUDY_MAIN = """
import json, sys
from train.study.cluster import local_cluster
from train.study.executor import StudyRunner, run_until_done_or_stopped
from train.study.spec import study_from_dict
from distributed import Client, Nanny
if __name__ == "__main__":
  study, folder, scratch, commands = json.loads(sys.argv[1])
  specs = {"w": {"cls": Nanny, "options": {"nthreads": 1, "resources": {"cpu": 1}, "local_directory": scratch,
                                           "env": {"TMPDIR": scratch, "FAKE_SLOW_SEED": "0"}}}}
  runner = StudyRunner(study_from_dict(study), folder, Client(local_cluster(specs)), tuple(map(tuple, commands)),
                       backends=("cpu",), progress_every=0.5)
  sys.exit(run_until_done_or_stopped(runner))
"""


def _cmdline(p) -> list[str]:
  """A process's command line; [] for one that ended (or is a zombie) since it was listed."""
  import psutil
  try:
    return p.cmdline()
  except psutil.Error:  # NoSuchProcess, ZombieProcess (a child exiting while the runner starts its runs)
    return []


@pytest.mark.parametrize("packed", [False, True])
def test_sigterm_to_a_study_stops_its_runs_with_their_checkpoints_and_leaves_nothing_behind(tmp_path, packed):
  """A scheduler's SIGTERM reaches the study process alone: it forwards it to the runs it started
  (one process per run, or one for a pack of seeds), which save; their folders come back; no run
  process nor scratch folder is left; exit 143."""
  import subprocess
  import sys

  import psutil
  scratch, folder = tmp_path / "scratch", str(tmp_path / "study")
  scratch.mkdir()
  seeds, prefix = ([0, 1], "study-pack-*") if packed else ([0], "study-cell-*")
  study = {**STUDY, "tasks": ["asc-inc-cog"], "seeds": seeds, "compare": [], "baselines": [],
           "groups": [{**STUDY["groups"][0], "pack_seeds": packed}]}
  proc = subprocess.Popen([sys.executable, "-c", _STUDY_MAIN, json.dumps([study, folder, str(scratch), COMMANDS])],
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
  t_end, runs = time.time() + 120, []
  while not runs:
    assert time.time() < t_end and proc.poll() is None, proc.stdout.read() if proc.poll() is not None else ""
    runs = [p for p in psutil.Process(proc.pid).children(recursive=True) if FAKE in " ".join(_cmdline(p))]
    time.sleep(0.2)
  while len({c.parent for c in scratch.glob(f"{prefix}/**/checkpoints/*")}) < len(seeds):  # a checkpoint of each run
    assert time.time() < t_end and proc.poll() is None, "no checkpoint in time"
    time.sleep(0.2)
  proc.send_signal(signal.SIGTERM)
  assert proc.wait(90) == 143, proc.stdout.read()
  assert not [p for p in runs if p.is_running() and p.status() != psutil.STATUS_ZOMBIE]
  assert len(runs) == 1  # a pack is one process
  records = json.load(open(os.path.join(folder, "state.json")))["cells"]
  for cell in cells(study_from_dict(study)):
    record = records[cell.id]
    assert record["status"] == "queued" and record["attempts"][-1]["stopped"] and record["attempts"][-1]["rc"] == 143
    assert os.listdir(os.path.join(cell_folder(folder, cell), "checkpoints"))  # came back: the next start resumes
  assert not list(scratch.glob(prefix))


def _the_timeline_shows_each_pack_as_one_program_then_the_retries(folder: str, spec) -> None:
  """`python -m train.study timeline`: the two packs (3 runs each), then seeds 0 and 1 of each task
  retried alone; each program's events in order (the database's times are to the second)."""
  progs = timeline.programs(folder)
  assert sorted(p.cells for p in progs[:2]) == sorted(tuple(f"g/{t}/400/s{s}" for s in (0, 1, 2)) for t in spec.tasks)
  assert sorted(p.cells for p in progs[2:]) == sorted((f"g/{t}/400/s{s}",) for t in spec.tasks for s in (0, 1))
  for p in progs:
    assert int(p.started) <= p.compiled <= p.trained <= p.ended + 1 and not p.stopped
  assert max(p.started for p in progs[:2]) < min(p.started for p in progs[2:])  # the retries after the packs
  said = timeline.lines("t", progs)
  assert said[0].startswith("study t: ") and "6 programs of 6 runs" in said[0] and len(said) == 8
  assert said[2].split()[:3] == [progs[0].cells[0], "+2", "3"]


def test_a_pack_of_seeds_trains_as_one_program_and_each_run_comes_back_as_its_own(tmp_path):
  """pack_seeds: a group's fresh runs that differ only in their seed are one train.run --seeds
  process per task (both tasks' packs at once, one slot each); each run's folder, records and
  evaluation come back as a single run's. In each pack seed 2 stops early at step 200, then seed 1
  crashes the program at step 300: seed 2 is evaluated as it ended (not trained on), seeds 0 and 1
  are retried alone from their own checkpoints, with no retries left to use (a pack's failure uses
  up none)."""
  study = {**STUDY, "seeds": [0, 1, 2], "baselines": [], "retries": 0,
           "groups": [{**STUDY["groups"][0], "pack_seeds": True}]}
  spec, folder = study_from_dict(study), str(tmp_path / "study")
  # workers whose JAX is not kept to the CPU: a pack's evaluation starts beside its training
  with local_cluster(_workers(tmp_path, slow="", FAKE_EARLY_SEED="2", FAKE_CRASH_STEP="300", JAX_PLATFORMS="")) \
       as cluster, Client(cluster) as client:
    counts = StudyRunner(spec, folder, client, COMMANDS, backends=("cpu",), stream=io.StringIO()).run()
  assert counts == {"done": 6, "running": 0, "queued": 0, "failed": 0}
  state = json.load(open(os.path.join(folder, "state.json")))["cells"]
  db = ExperimentDB(os.path.join(folder, STUDY_DB))
  for c in cells(spec):
    attempts, run = state[c.id]["attempts"], cell_folder(folder, c)
    assert attempts[0]["pack"] == [f"g/{c.task}/400/s{s}" for s in (0, 1, 2)]
    meta = json.load(open(os.path.join(run, "run.json")))
    checkpoints = sorted(int(d) for d in os.listdir(os.path.join(run, "checkpoints")))
    if c.seed == 2:  # ended by its early stop before the crash: evaluated, never trained again
      assert [(a["rc"], a["phase"]) for a in attempts] == [(0, "evaluate")]
      said = open(os.path.join(run, "study-attempts.log")).read()
      assert "evaluating 1 of 3 runs beside the training" in said  # the one that ended, named when the training did
      assert meta["programs"] == ["0,1,2"] and checkpoints[-1] == 200
      assert db.run(meta["run_id"])["status"] == "stopped_early"
    else:
      first, second = attempts
      assert first["rc"] == 1 and first["phase"] == "train" and "in a pack of 3 runs" in first["error"]
      assert "pack" not in second and second["resumed"] and second["rc"] == 0 and second["phase"] == "evaluate"
      assert meta["programs"] == ["0,1,2", str(c.seed)] and checkpoints[-1] == 400
    assert meta["seed"] == c.seed
    own = ExperimentDB(os.path.join(run, "run.sqlite")).runs()
    assert [r["run_id"] for r in own] == [meta["run_id"]]  # its own rows only, as a single run's
    trials = [e for e in db.evals(meta["run_id"]) if e["scene"] == "hardest" and e["budget"] is None]
    assert sum(e["success"] for e in trials) == sum(fake_success(c.task, c.seed, 400, i) for i in range(4))
    assert os.path.isdir(os.path.join(run, "milestones", "200"))
  starts = sorted(state[f"g/{t}/400/s0"]["attempts"][0]["started"] for t in spec.tasks)
  ends = sorted(state[f"g/{t}/400/s0"]["attempts"][0]["ended"] for t in spec.tasks)
  assert starts[1] < ends[0]  # the two packs ran at once
  _the_timeline_shows_each_pack_as_one_program_then_the_retries(folder, spec)
  [mine] = os.listdir(os.path.join(folder, ".handoff"))  # the study process's handoff folder
  assert os.listdir(os.path.join(folder, ".handoff", mine)) == ["token"]  # every folder moved in was taken
  assert all(a["returned"] == "moved" for c in state.values() for a in c["attempts"])  # all, the retries too


def test_a_pack_of_tasks_and_groups_trains_as_one_program_and_each_run_comes_back_as_its_own(tmp_path):
  """pack_tasks: the packs of seeds of a group's tasks that one program can take as data (here the
  sampler), and of a second group that differs only in its early stop, are one train.run --tasks ...
  --seeds ... --early-stops ... process; each run comes back in its own folder with its own records
  and evaluation."""
  group = {**STUDY["groups"][0], "budgets": "runs", "steps": [200], "pack_seeds": True, "pack_tasks": True}
  study = {**STUDY, "baselines": [], "compare": [], "groups": [group, {**group, "name": "r", "early_stop": "return"}]}
  spec, folder = study_from_dict(study), str(tmp_path / "study")
  with local_cluster(_workers(tmp_path, slow="", FAKE_CRASH_SEED="")) as cluster, Client(cluster) as client:
    counts = StudyRunner(spec, folder, client, COMMANDS, backends=("cpu",), stream=io.StringIO()).run()
  assert counts == {"done": 8, "running": 0, "queued": 0, "failed": 0}
  state = json.load(open(os.path.join(folder, "state.json")))["cells"]
  db = ExperimentDB(os.path.join(folder, STUDY_DB))
  for c in cells(spec):
    meta = json.load(open(os.path.join(cell_folder(folder, c), "run.json")))
    assert state[c.id]["attempts"][0]["pack"] == [f"{g}/{t}/200/s{s}" for g in "gr" for t in spec.tasks for s in (0, 1)]
    assert (meta["task"], meta["seed"], meta["programs"]) == (c.task, c.seed, ["0,1 x asc-inc-cog,asc-uni-cog x none,return"])
    own = ExperimentDB(os.path.join(cell_folder(folder, c), "run.sqlite")).runs()
    assert [r["run_id"] for r in own] == [meta["run_id"]]
    trials = [e for e in db.evals(meta["run_id"]) if e["scene"] == "hardest"]
    assert sum(e["success"] for e in trials) == sum(fake_success(c.task, c.seed, 200, i) for i in range(4))
    said = open(os.path.join(cell_folder(folder, c), "study-attempts.log")).read()
    assert "beside the training" not in said  # CPU workers: the evaluation starts after the training


def test_packs_join_across_tasks_only_where_one_program_takes_their_differences_as_data():
  """A pack_tasks group: tasks whose configs differ in data only (sampler, stair direction, reward
  kind) join one pack per set of fresh seeds; a task of another scene kind packs its seeds alone;
  without pack_tasks each task packs its own seeds."""
  from train.study.spec import pack_folders, pack_train_args, packs_of
  group = {**STUDY["groups"][0], "steps": [200], "pack_seeds": True, "pack_tasks": True}
  spec = study_from_dict({**STUDY, "tasks": ["asc-inc-cog", "des-uni-ang", "nav"], "baselines": [], "compare": [],
                          "groups": [group]})
  packs = packs_of(cells(spec))
  assert [[c.id for c in p] for p in packs] == [
      [f"g/{t}/200/s{s}" for t in ("asc-inc-cog", "des-uni-ang") for s in (0, 1)], ["g/nav/200/s0", "g/nav/200/s1"]]
  args = pack_train_args(packs[0])
  assert args[args.index("--tasks") + 1] == "asc-inc-cog,des-uni-ang" and args[args.index("--seeds") + 1] == "0,1"
  assert "--task" not in args and "--task" in pack_train_args(packs[1]) and "--tasks" not in pack_train_args(packs[1])
  assert pack_folders(packs[0]) == ["asc-inc-cog/s0", "asc-inc-cog/s1", "des-uni-ang/s0", "des-uni-ang/s1"]
  assert pack_folders(packs[1]) == ["s0", "s1"]
  partial = [c for c in cells(spec) if c.id != "g/des-uni-ang/200/s1"]  # des-uni-ang's seeds differ: not joined
  assert [len(p) for p in packs_of(partial)] == [2, 2]
  alone = study_from_dict({**STUDY, "baselines": [], "compare": [], "groups": [{**group, "pack_tasks": False}]})
  assert [len(p) for p in packs_of(cells(alone))] == [2, 2]
  with pytest.raises(ConfigError, match=r"groups\[0\]\.pack_tasks"):
    study_from_dict({**STUDY, "groups": [{**group, "pack_seeds": False}]})


def test_packs_join_across_groups_only_where_they_differ_in_their_early_stop_alone():
  """Groups whose runs differ only in their early stop (and name), with the same tasks and seeds,
  join one pack (train.run --early-stops, each run in stop-<criterion>/); groups that differ in
  anything else, in their seeds, or not in their early stop keep packs of their own."""
  from train.study.spec import pack_folders, pack_train_args, packs_of
  group = {**STUDY["groups"][0], "budgets": "runs", "steps": [200], "pack_seeds": True, "pack_tasks": True}
  study = {**STUDY, "baselines": [], "compare": []}

  def packs(*groups):
    return [[c.id for c in p] for p in packs_of(cells(study_from_dict({**study, "groups": list(groups)})))]
  two = (group, {**group, "name": "r", "early_stop": "return"})
  assert packs(*two) == [[f"{g}/{t}/200/s{s}" for g in "gr" for t in STUDY["tasks"] for s in (0, 1)]]
  [pack] = packs_of(cells(study_from_dict({**study, "groups": list(two)})))
  args = pack_train_args(pack)
  assert args[args.index("--early-stops") + 1] == "none,return" and "--early-stop" not in args
  assert pack_folders(pack)[:2] == ["stop-none/asc-inc-cog/s0", "stop-none/asc-inc-cog/s1"]
  assert pack_folders(pack)[-1] == "stop-return/asc-uni-cog/s1"
  for first, other in (({}, {"early_stop": "", "name": "same"}), ({}, {"set": ["reward.cog_scale=0.5"]}),
                       ({}, {"steps": [300]}), ({}, {"tasks": ["asc-inc-cog"]}), ({}, {"pack_tasks": False}),
                       ({}, {"early_stop": "success"}),  # probes its runs, where this preset probes none
                       ({"early_stop": "return"}, {"early_stop": "return=0.5"})):  # one criterion on both tasks
    found = packs({**group, **first}, {**two[1], **other})
    assert len(found) >= 2 and all(len({cid.split("/")[0] for cid in p}) == 1 for p in found), other
  partial = [c for c in cells(study_from_dict({**study, "groups": list(two)})) if c.id != "r/asc-uni-cog/200/s1"]
  assert [len(p) for p in packs_of(partial)] == [4, 2]  # r's seeds differ on asc-uni-cog: its own packs


def test_seeds_are_packed_only_for_this_projects_trainer():
  bad = {**STUDY, "groups": [{**STUDY["groups"][0], "budgets": "runs", "library": "sb3", "pack_seeds": True}]}
  with pytest.raises(ConfigError, match=r"groups\[0\]\.pack_seeds"):
    study_from_dict(bad)


def test_status_says_submitted_not_running_for_runs_handed_to_the_cluster(tmp_path):
  """state.json's "running" is any run handed to the cluster, with one slot or many: the status
  command cannot tell running from waiting, and says so."""
  folder = tmp_path / "s"
  folder.mkdir()
  cells_ = {f"g/t/1/s{i}": {"status": "running", "attempts": [{"started": 1.0}]} for i in range(4)}
  json.dump({"cells": cells_}, open(folder / "state.json", "w"))
  lines = summary(str(folder), runs=True)
  assert "4 not finished (4 submitted: running or waiting for a slot)" in lines[0]
  assert all(" submitted " in line and " running " not in line for line in lines[2:])


def test_status_reads_a_runs_hardest_success_from_its_report_or_else_from_the_study_database(tmp_path):
  """A committed study keeps no per-run reports: the success column then comes from the final
  evaluation's trials in study.sqlite (a milestone's trials left out), and reading it leaves no
  -wal / -shm files beside it."""
  from train.core.run_record import write_run_record
  folder = tmp_path / "s"
  folder.mkdir()
  state = {"cells": {"g/t/1/s0": {"status": "done", "attempts": [{"started": 1.0}]}}}
  json.dump(state, open(folder / "state.json", "w"))
  run = folder / "runs" / "g_t_1_s0"
  write_run_record(str(run), {"run_id": "r0"})
  db = ExperimentDB(str(folder / STUDY_DB))
  db.log_evals("r0", [{"scene": "hardest", "trial": i, "success": float(i < 3)} for i in range(4)])  # final: 0.75
  db.log_evals("r0", [{"scene": "hardest", "trial": 0, "success": 0.0, "budget": 500}])  # a milestone's
  db.log_evals("r0", [{"scene": "uniform", "trial": 0, "success": 0.0}])
  del db
  for side in ("-wal", "-shm"):
    (folder / (STUDY_DB + side)).unlink(missing_ok=True)  # as a committed study's file
  assert summary(str(folder), runs=True)[2].endswith(" 0.75")
  assert not list(folder.glob(STUDY_DB + "-*"))
  (run / "eval-hardest.json").write_text(json.dumps({"metrics": {"success": {"mean": 0.5}}}))
  assert summary(str(folder), runs=True)[2].endswith(" 0.50")  # a study under way: the report


def test_a_brax_run_is_evaluated_again_only_once_trained_and_else_trained_from_the_start(tmp_path):
  """Brax writes no checkpoints: a brax cell whose evaluation failed keeps its policy and is only
  evaluated again; one whose training failed is trained again from the start (nothing to resume)."""
  spec = study_from_dict({"name": "b", "tasks": ["asc-inc-cog"], "seeds": [0], "baselines": [],
                          "groups": [{"name": "brax", "algo": "ppo", "preset": "cpu", "steps": [64], "library": "brax"},
                                     {"name": "ours", "algo": "ppo", "preset": "cpu", "steps": [64]}]})
  brax, ours = cells(spec)
  run = tmp_path / "run"
  assert next_attempt(brax, str(run), []) == (False, True)  # the first attempt trains
  (run / "policy").mkdir(parents=True)
  (run / "policy" / "policy.json").write_text("{}")
  assert next_attempt(brax, str(run), [{"phase": "evaluate"}]) == (True, False)  # evaluate only
  assert next_attempt(brax, str(run), [{"phase": "train"}]) == (False, True)  # policy of an unfinished train
  assert next_attempt(ours, str(run), [{"phase": "evaluate"}]) == (False, True)  # ours needs checkpoints
  (run / "checkpoints" / "64").mkdir(parents=True)
  assert next_attempt(ours, str(run), [{"phase": "evaluate"}]) == (True, False)


def test_runs_a_study_stop_cut_off_before_a_checkpoint_are_packed_again(tmp_path):
  """A pack cut off by the machine going back (attempts 'stopped', no phase) and no checkpoint come
  back: its runs start afresh, so they are packed again (each ran alone before: 5 x 300 s instead of
  one program); a checkpoint, an ended attempt or a folder of unknown origin keeps a run alone."""
  spec = study_from_dict({**STUDY, "groups": [{**STUDY["groups"][0], "pack_seeds": True}]})
  cell = cells(spec)[0]
  folder = tmp_path / "run"
  cut = {"started": 1.0, "ended": None, "rc": None, "phase": None, "stopped": True}
  assert starts_afresh(cell, [], str(folder))  # never tried
  assert starts_afresh(cell, [cut, cut], str(folder))  # cut off twice, nothing came back
  (folder / "tb").mkdir(parents=True)
  assert not starts_afresh(cell, [], str(folder))  # a folder without any attempt: not the study's own
  assert starts_afresh(cell, [cut], str(folder))  # what a cut-off attempt left, without a checkpoint
  (folder / "checkpoints" / "200").mkdir(parents=True)
  assert not starts_afresh(cell, [cut], str(folder))  # resumes from its checkpoint
  shutil.rmtree(folder)
  failed = {"started": 1.0, "ended": 2.0, "rc": 1, "phase": "train", "pack": ["x"]}
  drained = {**failed, "rc": 143, "stopped": True}  # SIGTERM: its run saved and came back
  assert not starts_afresh(cell, [failed], str(folder)) and not starts_afresh(cell, [cut, drained], str(folder))


def test_the_study_line_gives_an_eta_only_while_runs_wait_for_a_slot():
  """Runs finished a second x runs left: where every run left is running (a pack's runs end
  together), that rate says nothing, and the line gives no ETA."""
  from train.study.executor import StudyState, _progress

  def line(done: int, running: int, queued: int, busy: int) -> str:
    status = ["done"] * done + ["running"] * running + ["queued"] * queued
    state = StudyState("unused", {f"c{i}": {"status": s, "attempts": []} for i, s in enumerate(status)})
    out = io.StringIO()
    _progress("p", state, time.time() - 100, done, busy, out)
    return out.getvalue()

  assert line(20, 40, 0, 40).startswith("[study] p: 20 done, 40 running, 0 waiting, 0 to retry, 0 failed | 100 s\n")
  assert line(20, 40, 0, 20).rstrip().endswith("| 100 s, eta 200 s")  # 20 waiting for a slot: 0.2 runs/s, 40 left
  assert line(20, 20, 10, 20).rstrip().endswith("| 100 s, eta 150 s")  # 10 to retry

"""Launching through the server: runs queued over the API run on a local Dask cluster (with the
stand-in runner of tests/fake_study_run.py), never in the server's process; the queue shows them
to the end; cancel, stop, resume and evaluate; a server restarted while a run ran queues it again
to resume from its checkpoints."""

import os
import pathlib
import time

import pytest
import scipy.stats
from distributed import Client, LocalCluster
from fake_study_run import fake_success
from fastapi.testclient import TestClient

from train.db import ExperimentDB, utc_now
from train.server.app import create_app
from train.server.launcher import Launcher
from train.server.settings import Settings

FAKE = str(pathlib.Path(__file__).with_name("fake_study_run.py"))
COMMANDS = ((FAKE, "train"), (FAKE, "evaluate"))

LOCAL = "http://127.0.0.1"  # a tokenless server answers only requests that name it by a loopback address


@pytest.fixture()
def cluster():
  with LocalCluster(n_workers=1, threads_per_worker=2, processes=False, resources={"cpu": 2},
                    dashboard_address=":0") as c, Client(c) as client:
    yield client


def _server(tmp_path, client):
  settings = Settings(str(tmp_path / "runs" / "experiments.sqlite"), str(tmp_path / "runs"))
  launcher = Launcher(settings.db, settings.runs_root, client, ("cpu",), COMMANDS, poll_s=0.1).start()
  return TestClient(create_app(settings, launcher), base_url=LOCAL), launcher


def _wait(client: TestClient, launch_id: int, status: str, timeout_s: float = 60) -> dict:
  t_end = time.time() + timeout_s
  while time.time() < t_end:
    launch = next(l for l in client.get("/api/launches").json() if l["id"] == launch_id)
    if launch["status"] == status:
      return launch
    time.sleep(0.1)
  raise AssertionError(f"launch {launch_id} never became {status}: {launch}")


def test_a_launched_run_trains_elsewhere_is_evaluated_and_shows_in_the_queue(tmp_path, cluster):
  client, launcher = _server(tmp_path, cluster)
  try:
    r = client.post("/api/launches", json={"task": "asc-inc-cog", "steps": 300, "seed": 2, "eval_trials": 4})
    assert r.status_code == 201
    done = _wait(client, r.json()["id"], "done")
    assert done["rc"] == 0 and done["out_dir"].endswith("asc-inc-cog-ppo-s2-L1")
    (run,) = client.get("/api/runs").json()
    assert run["status"] == "done" and run["step"] == 300 and run["seed"] == 2
    assert run["out_dir"] == done["out_dir"]
    evals = client.get(f"/api/runs/{run['run_id']}/evals").json()
    assert {e["scene"] for e in evals} == {"hardest", "uniform", "held-out/middle"}  # the stand-in's suite
    assert (client.post(f"/api/runs/{run['run_id']}/stop").json()["detail"]
            == f"run {run['run_id']} is done; nothing to stop")
    assert client.post(f"/api/runs/{run['run_id']}/resume").status_code == 409
    again = client.post(f"/api/runs/{run['run_id']}/evaluate")
    assert _wait(client, again.json()["id"], "done")["out_dir"] == done["out_dir"]
    assert client.delete(f"/api/launches/{again.json()['id']}").json()["detail"].endswith("nothing to cancel")
  finally:
    launcher.stop()


def test_bad_launches_are_refused_naming_the_field(tmp_path, cluster):
  client, launcher = _server(tmp_path, cluster)
  try:
    r = client.post("/api/launches", json={"task": "asc-inc-cog", "overrides": ["reward.cog_scal=1"]})
    assert r.status_code == 422 and r.json()["detail"][0]["loc"] == ["body", "overrides", "reward.cog_scal"]
    assert client.post("/api/launches", json={"task": "nope"}).status_code == 422
    assert client.post("/api/launches", json={"task": "asc-inc-cog", "preset": "huge"}).status_code == 422
    bad_hp = client.post("/api/launches", json={"task": "asc-inc-cog", "hp": ["discounting=2"]})
    assert bad_hp.status_code == 422 and "--hp discounting: a number in [0, 1]" in bad_hp.json()["detail"][0]["msg"]
    brax = client.post("/api/launches", json={"task": "asc-inc-cog", "library": "brax", "early_stop": "success"})
    assert brax.status_code == 422 and "brax has no early stop" in brax.json()["detail"][0]["msg"]
    assert client.delete("/api/launches/99").status_code == 404
    assert client.post("/api/runs/zzz/stop").status_code == 404
    assert client.get("/api/launches").json() == []
  finally:
    launcher.stop()


def test_stop_cancel_and_a_server_restart_that_resumes_the_run(tmp_path, cluster, monkeypatch):
  monkeypatch.setenv("FAKE_SLOW_SEED", "0")  # 1 s per 100 steps
  client, launcher = _server(tmp_path, cluster)
  first = client.post("/api/launches", json={"task": "asc-inc-cog", "steps": 3000, "seed": 0}).json()["id"]
  queued = client.post("/api/launches", json={"task": "asc-uni-cog", "steps": 3000, "seed": 0}).json()["id"]
  db = ExperimentDB(str(tmp_path / "runs" / "experiments.sqlite"))
  t_end = time.time() + 60
  while not [r for r in db.runs() if r["task"] == "asc-inc-cog" and r["status"] == "running"]:
    assert time.time() < t_end
    time.sleep(0.1)
  assert client.delete(f"/api/launches/{queued}").status_code == 200  # cancelled, whether it started or not
  _wait(client, queued, "cancelled")
  launcher.stop()  # the server stops while its run goes on (the run's process is the cluster's)
  time.sleep(1.5)
  client, launcher = _server(tmp_path, cluster)  # started again: it follows the run that still runs
  try:
    (run,) = [r for r in client.get("/api/runs").json() if r["task"] == "asc-inc-cog"]
    assert run["status"] == "running" and first in launcher.futures
    assert [e["event"] for e in client.get(f"/api/runs/{run['run_id']}").json()["events"]] == ["started", "compiled"]
    assert client.post(f"/api/runs/{run['run_id']}/stop").json()["detail"].endswith("stop requested")
    stopped = _wait(client, first, "stopped")
    assert stopped["rc"] == 143 and client.get(f"/api/runs/{run['run_id']}").json()["status"] == "interrupted"
    assert os.path.isdir(os.path.join(stopped["out_dir"], "checkpoints"))
    resumed = client.post(f"/api/runs/{run['run_id']}/resume")
    assert resumed.status_code == 201
    _wait(client, resumed.json()["id"], "running")
    t_end = time.time() + 30
    while "resumed" not in [e["event"] for e in client.get(f"/api/runs/{run['run_id']}").json()["events"]]:
      assert time.time() < t_end
      time.sleep(0.1)
    time.sleep(0.3)  # its SIGTERM handler is set up after the record (a stop before it kills: -15)
    assert client.post(f"/api/runs/{run['run_id']}/stop").json()["detail"].endswith("stop requested")
    assert _wait(client, resumed.json()["id"], "stopped")["rc"] == 143
    events = [e["event"] for e in client.get(f"/api/runs/{run['run_id']}").json()["events"]]
    assert events == ["started", "compiled", "interrupted", "resumed", "compiled", "interrupted"]
  finally:
    launcher.stop()


def _slow_run_running(tmp_path, client) -> tuple[int, ExperimentDB]:
  """(launch id, database) of a 30 s launch (3,000 steps at 1 s per 100) once its run is running."""
  lid = client.post("/api/launches", json={"task": "asc-inc-cog", "steps": 3000, "seed": 0}).json()["id"]
  db = ExperimentDB(str(tmp_path / "runs" / "experiments.sqlite"))
  t_end = time.time() + 60
  while not [r for r in db.runs() if r["status"] == "running"]:
    assert time.time() < t_end
    time.sleep(0.1)
  return lid, db


def _stopped_soon(db: ExperimentDB, lid: int, timeout_s: float = 15) -> None:
  t_end = time.time() + timeout_s
  while db.runs()[0]["status"] == "running":
    assert time.time() < t_end, "the cancelled launch's run still runs"
    time.sleep(0.1)
  assert db.runs()[0]["status"] == "interrupted" and db.launch(lid)["status"] == "cancelled"


def test_a_launch_cancelled_before_its_process_is_known_has_its_run_stopped_once_it_is(tmp_path, cluster, monkeypatch):
  """The cancel's look for the run's process finds none (as when the run is just starting, or
  between its training and its evaluation): the launcher looks again at its next ticks and stops it,
  rather than let it run on (here 30 s) in a slot Dask believes free."""
  from train.server import launcher as launcher_module
  monkeypatch.setenv("FAKE_SLOW_SEED", "0")
  client, launcher = _server(tmp_path, cluster)
  try:
    lid, db = _slow_run_running(tmp_path, client)
    real, missed = launcher_module.stop_run_in, []
    monkeypatch.setattr(launcher_module, "stop_run_in",
                        lambda *a: real(*a) if missed else missed.append(1) or False)  # the first look misses
    assert client.delete(f"/api/launches/{lid}").json()["detail"].endswith("cancelled")
    _stopped_soon(db, lid)
    assert missed == [1]
  finally:
    launcher.stop()


def test_a_restarted_server_stops_the_run_of_a_launch_cancelled_as_the_server_stopped(tmp_path, cluster, monkeypatch):
  """Cancelled (recorded so) and the server gone before it stopped the run: the restarted server
  stops the process its pid file names."""
  monkeypatch.setenv("FAKE_SLOW_SEED", "0")
  client, launcher = _server(tmp_path, cluster)
  lid, db = _slow_run_running(tmp_path, client)
  launcher.stop()
  db.set_launch(lid, status="cancelled", ended=utc_now())  # as Launcher.cancel records it, before its SIGTERM
  client, launcher = _server(tmp_path, cluster)
  try:
    _stopped_soon(db, lid)
  finally:
    launcher.stop()


def test_a_launch_whose_run_died_with_the_server_is_queued_to_resume(tmp_path, cluster):
  """What a restart finds when the cluster died with the server: a 'running' launch whose run
  left a checkpoint and no live process; it is queued again as a resume of that folder."""
  runs = tmp_path / "runs"
  out = runs / "asc-inc-cog-ppo-s0-L1"
  (out / "checkpoints" / "100").mkdir(parents=True)
  db = ExperimentDB(str(runs / "experiments.sqlite"))
  lid = db.add_launch("run", {"task": "asc-inc-cog", "steps": 300}, str(out))
  db.set_launch(lid, status="running")
  launcher = Launcher(db.path, str(runs), cluster, ("cpu",), COMMANDS, poll_s=3600).start()  # no tick
  try:
    launch = db.launch(lid)
    assert (launch["status"], launch["kind"], launch["out_dir"]) == ("queued", "resume", str(out))
  finally:
    launcher.stop()


STUDY_YAML = """name: web
tasks: [asc-inc-cog, asc-uni-cog]
seeds: [0, 1]
eval_trials: 4
groups:
  - {name: g, algo: ppo, preset: cpu, steps: [200], backend: cpu}
baselines: []
"""


def test_a_study_launched_through_the_server_runs_every_run_and_lists_them(tmp_path, cluster):
  client, launcher = _server(tmp_path, cluster)
  try:
    bad = client.post("/api/studies", json={"yaml": STUDY_YAML, "overrides": ["seeds=[0, 0]"]})
    assert bad.status_code == 422 and "seeds" in bad.json()["detail"][0]["msg"]
    assert client.post("/api/studies", json={"yaml": "name: [unclosed"}).status_code == 422
    r = client.post("/api/studies", json={"yaml": STUDY_YAML})
    assert r.status_code == 201 and r.json()["folder"].endswith(os.path.join("runs", "studies", "web"))
    _wait(client, r.json()["id"], "done")
    (study,) = client.get("/api/studies").json()
    assert (study["runs"], study["done"], study["failed"], len(study["run_ids"])) == (4, 4, 0, 4)
    runs = client.get("/api/runs").json()  # mirrored from the study's own database
    assert sorted((x["task"], x["seed"], x["status"]) for x in runs) == [
        ("asc-inc-cog", 0, "done"), ("asc-inc-cog", 1, "done"), ("asc-uni-cog", 0, "done"), ("asc-uni-cog", 1, "done")]
    assert os.path.exists(os.path.join(r.json()["folder"], "study.log"))
    groups = client.get(f"/api/studies/{r.json()['id']}/groups").json()
    success = [c for c in groups["curves"] if c["metric"] == "success_rate"]
    assert sorted((c["group"], c["task"], c["runs"]) for c in success) == [("g", "asc-inc-cog", 2), ("g", "asc-uni-cog", 2)]
    for c in success:  # the stand-in logs success = step / 1000 for every seed: a band of width 0
      assert c["mean"] == pytest.approx([x / 1000 for x in c["x"]]) and c["low"] == pytest.approx(c["high"])
    (inc,) = [f for f in groups["final"] if f["task"] == "asc-inc-cog"]
    per_seed = [sum(fake_success("asc-inc-cog", seed, 200, i) for i in range(4)) / 4 for seed in (0, 1)]
    iqm = scipy.stats.trim_mean(per_seed, 0.25)
    assert inc["iqm"]["success hardest"][0] == pytest.approx(iqm)
    assert client.get("/api/studies/99/groups").status_code == 404
  finally:
    launcher.stop()


def test_cancelling_a_study_cancels_its_waiting_runs(tmp_path, cluster, monkeypatch):
  monkeypatch.setenv("FAKE_SLOW_SEED", "0")
  client, launcher = _server(tmp_path, cluster)
  try:
    slow = STUDY_YAML.replace("steps: [200]", "steps: [300]").replace("seeds: [0, 1]", "seeds: [0]")
    r = client.post("/api/studies", json={"yaml": slow, "overrides": ["tasks=[asc-inc-cog, asc-uni-cog, des-inc-ang]"]})
    _wait(client, r.json()["id"], "running")
    assert client.delete(f"/api/launches/{r.json()['id']}").json()["detail"].endswith("cancelled")
    launch = _wait(client, r.json()["id"], "cancelled")
    (study,) = client.get("/api/studies").json()
    assert study["done"] < 3 and launch["ended"]
  finally:
    launcher.stop()


def _record_process(out, pid: int, phase: str) -> None:
  import json
  import socket
  with open(f"{out}.pid", "w") as f:
    json.dump({"pid": pid, "host": socket.gethostname(), "phase": phase}, f)


def test_a_launch_that_cannot_start_is_recorded_failed_and_the_queue_goes_on(tmp_path, cluster):
  client, launcher = _server(tmp_path, cluster)
  db = ExperimentDB(str(tmp_path / "runs" / "experiments.sqlite"))
  try:
    broken = db.add_launch("run", {"task": "no-such-task", "steps": 100}, None)  # e.g. queued by an older version
    good = client.post("/api/launches", json={"task": "asc-inc-cog", "steps": 200, "eval_trials": 0}).json()["id"]
    failed = _wait(client, broken, "failed")
    assert failed["error"].startswith("could not start: ConfigError") and "no-such-task" in failed["error"]
    assert _wait(client, good, "done")["rc"] == 0  # the launcher thread lives on
  finally:
    launcher.stop()


def test_a_restart_reconciles_each_running_launch_with_what_it_finds(tmp_path, cluster):
  """After a SIGKILL of the server: a run that finished meanwhile is done (no resume, which
  train.run would refuse) or queued for the evaluation it asked for; a launch whose process still
  runs is followed until it ends; a stop reaches that process in its evaluation phase too."""
  import subprocess
  import sys
  runs = tmp_path / "runs"
  db = ExperimentDB(str(runs / "experiments.sqlite"))
  outs = {name: runs / name for name in ("finished", "unevaluated", "evaluating")}
  for i, (name, out) in enumerate(outs.items()):
    (out / "checkpoints" / "300").mkdir(parents=True)
    db.start(name, "asc-inc-cog", "ppo", "cpu", 0, {}, str(out), 300)
    db.finish(name, "done", {"step": 300}, 300)
  db.log_evals("finished", [{"scene": "hardest", "trial": 0, "progress": 1.0, "success": 1, "cog_deviation": 0.0,
                             "pitch_rate": 0.0, "tipped_over": 0, "length": 10}])
  ids = {name: db.add_launch("run", {"task": "asc-inc-cog", "steps": 300, "eval_trials": 4}, str(out))
         for name, out in outs.items()}
  for lid in ids.values():
    db.set_launch(lid, status="running")
  # a stand-in train.evaluate of that folder: its command line names it, as the real one's does
  evaluator = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)", str(outs["evaluating"])])
  _record_process(outs["evaluating"], evaluator.pid, "evaluate")
  launcher = Launcher(db.path, str(runs), cluster, ("cpu",), COMMANDS, poll_s=3600).start()  # no tick
  try:
    assert db.launch(ids["finished"])["status"] == "done"
    assert (db.launch(ids["unevaluated"])["status"], db.launch(ids["unevaluated"])["kind"]) == ("queued", "evaluate")
    assert db.launch(ids["evaluating"])["status"] == "running" and ids["evaluating"] in launcher.futures
    client = TestClient(create_app(Settings(db.path, str(runs)), launcher), base_url=LOCAL)
    assert client.post("/api/runs/evaluating/stop").json()["detail"].endswith("stop requested")
    assert evaluator.wait(10) == -15  # SIGTERM reached the evaluation
    launcher._tick()
    assert db.launch(ids["evaluating"])["status"] == "done"  # its run's record says how it ended
  finally:
    evaluator.kill()
    launcher.stop()


def test_a_stale_pid_file_naming_another_process_stops_nothing(tmp_path):
  """A worker that died leaves its run's pid file; the pid may belong to another process since. Only
  a live process of this host whose command line names the run's folder is the run's: it alone is
  stopped (and followed after a restart)."""
  import signal
  import socket
  import subprocess
  import sys
  from train.server.launcher import named_process, stop_named_process
  from train.study.worker import pid_file
  out = str(tmp_path / "run")
  sleep = "import time; time.sleep(60)"
  other = subprocess.Popen([sys.executable, "-c", sleep])
  ours = subprocess.Popen([sys.executable, "-c", sleep, "--out", out])
  try:
    for proc, named in ((other, False), (ours, True)):
      pathlib.Path(pid_file(out)).write_text(f'{{"pid": {proc.pid}, "host": "{socket.gethostname()}", "phase": "train"}}')
      assert (named_process(out) is not None) == named and stop_named_process(out) == named
    assert ours.wait(10) == -signal.SIGTERM
    assert other.poll() is None  # not signalled
  finally:
    other.kill()
    ours.kill()

"""The server's REST API (FastAPI TestClient) over a database made here: run lists with their
latest figures, one run's record, statistics, evaluations and policy, configuration checked by the
command line's loader, and bad input: unknown runs, paths outside the runs folder, the token."""

import io
import os
import zipfile

import pytest
from fastapi.testclient import TestClient

from train.db import ExperimentDB
from train.server.__main__ import main as server_main
from train.server.app import create_app
from train.server.settings import Settings

LOCAL = "http://127.0.0.1"  # a tokenless server answers only requests that name it by a loopback address


@pytest.fixture()
def served(tmp_path):
  """(settings, run ids): run 'a' done with statistics, evaluations and a policy under the runs
  folder; run 'b' running, its folder outside the runs folder."""
  root = tmp_path / "runs"
  (root / "a" / "policy" / "params").mkdir(parents=True)
  (root / "a" / "policy" / "policy.json").write_text('{"step": 300}')
  (root / "a" / "policy" / "params" / "data").write_bytes(b"\x00" * 10)
  db = ExperimentDB(str(root / "experiments.sqlite"))
  db.start("a", "asc-inc-cog", "ppo", "cpu", 0, {"task": "asc-inc-cog"}, str(root / "a"), 300)
  for step, ret in ((100, 0.1), (200, 0.2), (300, 0.4)):
    db.log_stats("a", {"step": step, "wall_s": step / 10, "steps_per_s": 50.0 + step, "eps": step / 1000,
                       "return_mean": ret, "success_rate": ret / 2, "source": "train"}, {})
  db.log_stats("a", {"step": 300, "success_rate": 0.9, "source": "probe"}, {})
  db.log_evals("a", [{"scene": "hardest", "trial": i, "progress": 0.5 + i / 10, "success": i % 2,
                      "cog_deviation": 0.1, "pitch_rate": 0.2, "tipped_over": 0, "length": 10} for i in range(4)])
  db.finish("a", "done", {"step": 300}, 300)
  db.start("b", "des-inc-ang", "sac", "paper", 3, {}, str(tmp_path / "elsewhere"), 1000)
  return Settings(str(root / "experiments.sqlite"), str(root)), ("a", "b")


def test_the_run_list_holds_every_run_with_its_latest_training_figures(served):
  settings, _ = served
  runs = {r["run_id"]: r for r in TestClient(create_app(settings), base_url=LOCAL).get("/api/runs").json()}
  a, b = runs["a"], runs["b"]
  assert (a["status"], a["task"], a["algo"], a["seed"], a["step"], a["steps_per_s"]) == ("done", "asc-inc-cog", "ppo", 0, 300, 350.0)
  assert (a["return_mean"], a["success_rate"], a["eps"]) == (0.4, 0.2, 0.3)  # the train row, not the probe
  assert a["duration_s"] >= 0 and b["status"] == "running" and b["step"] is None


def test_one_run_its_statistics_evaluations_and_unknown_runs(served):
  settings, _ = served
  client = TestClient(create_app(settings), base_url=LOCAL)
  run = client.get("/api/runs/a").json()
  assert run["config"] == {"task": "asc-inc-cog"} and run["final"] == {"step": 300}
  assert [e["event"] for e in run["events"]] == ["started", "finished"]
  assert [r["step"] for r in client.get("/api/runs/a/stats", params={"source": "train"}).json()] == [100, 200, 300]
  assert len(client.get("/api/runs/a/stats").json()) == 4
  (ev,) = client.get("/api/runs/a/evals").json()
  assert (ev["scene"], ev["budget"], ev["trials"]) == ("hardest", None, 4)
  assert ev["mean"]["progress"] == pytest.approx((0.5 + 0.6 + 0.7 + 0.8) / 4) and ev["mean"]["success"] == 0.5
  for path in ("/api/runs/zzz", "/api/runs/zzz/stats", "/api/runs/zzz/evals", "/api/runs/zzz/policy"):
    r = client.get(path)
    assert r.status_code == 404 and "zzz" in r.json()["detail"]


def test_the_policy_downloads_as_a_zip_only_from_inside_the_runs_folder(served, tmp_path):
  settings, _ = served
  client = TestClient(create_app(settings), base_url=LOCAL)
  r = client.get("/api/runs/a/policy")
  assert r.status_code == 200 and r.headers["content-type"] == "application/zip"
  names = zipfile.ZipFile(io.BytesIO(r.content)).namelist()
  assert sorted(names) == ["policy/params/data", "policy/policy.json"]
  (tmp_path / "elsewhere" / "policy").mkdir(parents=True)
  r = client.get("/api/runs/b/policy")
  assert r.status_code == 403 and "outside the server's runs folder" in r.json()["detail"]
  os.symlink(tmp_path / "elsewhere" / "policy", tmp_path / "runs" / "a" / "policy-link")
  with pytest.raises(ValueError):  # a link out of the folder is outside too
    settings.inside_runs(str(tmp_path / "runs" / "a" / "policy-link"))


def test_configurations_are_checked_by_the_command_lines_loader_and_errors_name_the_field(served):
  settings, _ = served
  client = TestClient(create_app(settings), base_url=LOCAL)
  assert "asc-inc-cog" in client.get("/api/tasks").json()
  from train.core.plan import DEFAULT_LIBRARY, LIBRARIES
  from train.core.presets import PRESETS
  trainers = client.get("/api/trainers").json()  # the form's choices come from train.core, not a copy
  assert trainers["algos"] == {a: list(p) for a, p in PRESETS.items()} and trainers["libraries"] == LIBRARIES
  assert trainers["default_library"] == DEFAULT_LIBRARY and trainers["algos"]["sac"] == ["cpu", "gpu", "paper"]
  assert trainers["library_algos"]["sb3"]["td3"] == ["paper", "cpu", "gpu"]  # each library its own presets
  assert trainers["library_algos"][DEFAULT_LIBRARY] == trainers["algos"]
  ok = client.post("/api/validate", json={"task": "asc-inc-cog", "overrides": ["reward.cog_scale=0.5"]})
  assert ok.status_code == 200 and ok.json()["config"]["reward"]["cog_scale"] == 0.5
  cases = {("asc-inc-cog", "reward.cog_scal=1"): ["body", "overrides", "reward.cog_scal"],
           ("asc-inc-cog", "episode.max_steps=0"): ["body", "overrides", "episode.max_steps"],
           ("asc-inc-cog", "scene.riser=[0.3, 0.1]"): ["body", "overrides", "scene.riser"],
           ("nope", "reward.cog_scale=1"): ["body", "task"],
           ("asc-inc-cog", "robot=2"): ["body", "overrides", "control.mode"],  # the scene kinds' and robots' checks
           ("step-up", "reward.kind=cog"): ["body", "overrides", "reward.kind"],
           ("nav", "scene.nav_kinds=[maze]"): ["body", "overrides", "scene.nav_kinds"]}
  for (task, item), loc in cases.items():
    r = client.post("/api/validate", json={"task": task, "overrides": [item]})
    assert r.status_code == 422 and r.json()["detail"][0]["loc"] == loc, (item, r.json())
  assert client.post("/api/validate", json={"overrides": []}).status_code == 422  # no task: FastAPI's own check


def test_a_token_guards_every_call_and_binding_beyond_this_machine_needs_one(served, capsys):
  settings, _ = served
  client = TestClient(create_app(Settings(settings.db, settings.runs_root, token="s3cret")), base_url=LOCAL)
  for path in ("/api/runs", "/api/runs/a", "/api/tasks"):
    assert client.get(path).status_code == 401
    assert client.get(path, headers={"Authorization": "Bearer wrong"}).status_code == 401
    assert client.get(path, headers={"Authorization": "Bearer s3cret"}).status_code == 200
  assert client.post("/api/validate", json={"task": "asc-inc-cog"}).status_code == 401
  assert server_main(["--host", "0.0.0.0", "--db", settings.db]) == 2
  assert "needs a token" in capsys.readouterr().err


def test_the_openapi_document_lists_every_endpoint(served):
  settings, _ = served
  client = TestClient(create_app(settings), base_url=LOCAL)
  paths = set(client.get("/openapi.json").json()["paths"])
  assert {"/api/runs", "/api/runs/{run_id}", "/api/runs/{run_id}/stats", "/api/runs/{run_id}/evals",
          "/api/runs/{run_id}/policy", "/api/tasks", "/api/validate"} <= paths
  docs = client.get("/docs")
  assert docs.status_code == 200 and "/openapi.json" in docs.text
  assert "http" not in docs.text.replace("http-equiv", "")  # nothing loaded from the internet


def test_compare_puts_the_baselines_of_the_same_tasks_beside_the_runs(served):
  """Each scene's row: the runs' means, and each baseline run (algo 'baseline') of a compared run's
  task on that scene; a baseline of another task is left out."""
  settings, _ = served
  db = ExperimentDB(settings.db)
  for run_id, task, name, success in (("full-asc", "asc-inc-cog", "full", 1), ("full-des", "des-inc-ang", "full", 0)):
    db.start(run_id, task, "baseline", name, 0, {}, settings.runs_root, 0)
    db.log_evals(run_id, [{"scene": "hardest", "trial": i, "progress": 1.0, "success": success,
                           "cog_deviation": 0.1, "pitch_rate": 0.6, "tipped_over": 0, "length": 10} for i in range(3)])
    db.finish(run_id, "done")
  (row,) = TestClient(create_app(settings), base_url=LOCAL).get("/api/compare", params={"run": "a"}).json()
  assert row["scene"] == "hardest" and row["per_run"]["a"]["success"] == 0.5
  assert row["baselines"] == {"asc-inc-cog/full": {"success": 1.0, "progress": 1.0, "pitch_rate": pytest.approx(0.6)}}
  (row,) = TestClient(create_app(settings), base_url=LOCAL).get("/api/compare", params={"run": ["a", "b"]}).json()
  assert set(row["baselines"]) == {"asc-inc-cog/full", "des-inc-ang/full"}  # one name, two tasks: both kept
  assert row["baselines"]["des-inc-ang/full"]["success"] == 0.0

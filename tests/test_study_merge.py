"""`train.study merge`: a study whose runs were finished in another folder (another machine) gets
those runs' folders, database rows and attempts, and then reports exactly what the study that ran
everything in one place reports."""

import json
import os
import pathlib
import shutil
import sqlite3

import pytest
from distributed import Client

from train.db import ExperimentDB
from train.core.run_record import run_id_in
from train.study.executor import STUDY_DB, StudyRunner, cell_folder_of, read_cells
from train.study.merge import main as merge_main, merge
from train.study.report import final_table, report_text
from train.study.results import load_results
from train.study.spec import load_study, study_from_dict

FAKE = str(pathlib.Path(__file__).with_name("fake_study_run.py"))
COMMANDS = ((FAKE, "train"), (FAKE, "evaluate"))  # after the worker's Python
STUDY = {"name": "m", "tasks": ["asc-inc-cog", "asc-uni-cog"], "seeds": [0, 1], "retries": 0, "eval_trials": 4,
         "groups": [{"name": "g", "algo": "ppo", "preset": "cpu", "steps": [200], "backend": "cpu"}],
         "compare": [["asc-inc-cog", "asc-uni-cog"]], "baselines": ["zero"]}
UNFINISHED = ("g/asc-inc-cog/200/s1", "g/asc-uni-cog/200/s1")  # stopped in DEST, finished in SRC
NO_FOLDER = "g/asc-uni-cog/200/s0"  # done in DEST, but its run folder and rows did not come back
STOPPED = {"started": 1.0, "ended": None, "rc": None, "stopped": True, "error": "the study stopped"}


def _run_study(spec: dict, folder: str) -> dict:
  """The study run in `folder` by the study runner (the stand-in train.run) on a local cluster; its counts."""
  with Client(processes=False, n_workers=1, threads_per_worker=2, resources={"cpu": 2}, dashboard_address=":0") as c:
    return StudyRunner(study_from_dict(spec), folder, c, COMMANDS, backends=("cpu",)).run()


@pytest.fixture(scope="module")
def finished(tmp_path_factory) -> str:
  """The whole study run in one folder."""
  folder = str(tmp_path_factory.mktemp("full") / "m")
  assert _run_study(STUDY, folder)["done"] == 4 + 2  # and the zero baseline on each task
  return folder


def _forget(folder: str, cid: str, stopped: bool) -> str:
  """Removes a cell's run folder and database rows; stopped: its state says an attempt was cut off."""
  run_id = run_id_in(cell_folder_of(folder, cid))
  shutil.rmtree(cell_folder_of(folder, cid))
  with sqlite3.connect(os.path.join(folder, STUDY_DB)) as c:
    for table in ("evals", "events", "stats", "experiments"):
      c.execute(f"DELETE FROM {table} WHERE run_id=?", (run_id,))
    c.execute("DELETE FROM attempts WHERE cell=?", (cid,))
  path = os.path.join(folder, "state.json")
  state = json.load(open(path))
  if stopped:
    state["cells"][cid] = {"status": "queued", "attempts": [dict(STOPPED)]}
  json.dump(state, open(path, "w"))
  return run_id


def _evals(folder: str, run_id: str) -> list[tuple]:
  return [(e["scene"], e["budget"], e["trial"], e["success"]) for e in ExperimentDB(os.path.join(folder, STUDY_DB)).evals(run_id)]


def test_merging_the_runs_finished_elsewhere_gives_the_report_of_the_whole_study(finished, tmp_path):
  dest = str(tmp_path / "m")
  shutil.copytree(finished, dest)
  gone = {cid: _forget(dest, cid, stopped=True) for cid in UNFINISHED}
  gone[NO_FOLDER] = _forget(dest, NO_FOLDER, stopped=False)
  assert merge(dest, finished) == sorted(gone)
  full, merged = read_cells(finished), read_cells(dest)
  assert all(c["status"] == "done" for c in merged.values())
  for cid, run_id in gone.items():
    assert run_id_in(cell_folder_of(dest, cid)) == run_id
    assert _evals(dest, run_id) == _evals(finished, run_id) and len(_evals(dest, run_id)) > 0
    before = [] if cid == NO_FOLDER else [STOPPED]
    assert merged[cid]["attempts"] == before + full[cid]["attempts"]
    rows = [a for a in ExperimentDB(os.path.join(dest, STUDY_DB)).attempts("m") if a["cell"] == cid]
    assert [a["attempt"] for a in rows] == list(range(len(before) + 1, len(merged[cid]["attempts"]) + 1))
  assert merge(dest, finished) == []  # nothing left to merge
  tables = lambda folder: [line for line in report_text(load_results(folder), [], "cmd").splitlines()  # noqa: E731
                           if line.startswith("|")]  # every table of the report, without drawing its figures
  assert tables(dest) == tables(finished)


def test_a_study_continued_from_a_copy_of_dest_brings_dests_attempts_once(finished, tmp_path):
  dest, src, cid = str(tmp_path / "dest"), str(tmp_path / "src"), UNFINISHED[0]
  shutil.copytree(finished, dest)
  _forget(dest, cid, stopped=True)
  shutil.copytree(finished, src)  # SRC began as DEST (its stopped attempt first), then finished the run
  path = os.path.join(src, "state.json")
  state = json.load(open(path))
  own = state["cells"][cid]["attempts"]
  state["cells"][cid]["attempts"] = [dict(STOPPED)] + own
  json.dump(state, open(path, "w"))
  with sqlite3.connect(os.path.join(src, STUDY_DB)) as c:
    c.execute("UPDATE attempts SET attempt=attempt+1 WHERE cell=?", (cid,))
  assert merge(dest, src) == [cid]
  assert read_cells(dest)[cid]["attempts"] == [STOPPED] + own
  rows = [a["attempt"] for a in ExperimentDB(os.path.join(dest, STUDY_DB)).attempts("m") if a["cell"] == cid]
  assert rows == list(range(2, len(own) + 2))


def test_a_study_grown_in_src_gives_dest_its_spec_and_its_new_runs(finished, tmp_path):
  import yaml
  dest = str(tmp_path / "dest")
  shutil.copytree(finished, dest)
  new = [cid for cid in read_cells(finished) if cid.endswith("/s1")]  # seed 1 was added to the study in SRC
  for cid in new:
    _forget(dest, cid, stopped=False)
  state = json.load(open(os.path.join(dest, "state.json")))
  state["cells"] = {cid: c for cid, c in state["cells"].items() if cid not in new}
  json.dump(state, open(os.path.join(dest, "state.json"), "w"))
  spec = yaml.safe_load(open(os.path.join(dest, "study.yaml")))
  yaml.safe_dump({**spec, "seeds": [0]}, open(os.path.join(dest, "study.yaml"), "w"), sort_keys=False)
  assert merge(dest, finished) == sorted(new)
  assert yaml.safe_load(open(os.path.join(dest, "study.yaml")))["seeds"] == [0, 1]
  assert read_cells(dest) == read_cells(finished)
  assert final_table(load_results(dest)) == final_table(load_results(finished))  # the tables, without drawing figures


def test_a_folder_of_another_study_is_refused(finished, tmp_path, capsys):
  other = str(tmp_path / "other")
  shutil.copytree(finished, other)
  text = open(os.path.join(other, "study.yaml")).read()
  open(os.path.join(other, "study.yaml"), "w").write(text.replace("name: m", "name: other", 1))
  assert merge_main([finished, other]) == 2
  assert "holds study 'other'" in capsys.readouterr().err
  assert merge_main([finished, str(tmp_path / "nothing")]) == 2


def test_a_src_that_ran_new_groups_alone_adds_them_and_their_runs_to_dest(finished, tmp_path, capsys):
  """`python -m train.study NAME --set 'groups=[...]'` run elsewhere (new groups, no baselines): its
  groups join DEST's study.yaml beside DEST's own, their runs come, DEST's runs stay as they were;
  a group of one name that differs between the two is refused in one line, DEST unchanged."""
  import yaml
  src = str(tmp_path / "new" / "m")
  new_group = {"name": "h", "algo": "ppo", "preset": "cpu", "steps": [100], "backend": "cpu"}
  assert _run_study({**STUDY, "groups": [new_group], "baselines": []}, src)["done"] == 4
  dest = str(tmp_path / "dest")
  shutil.copytree(finished, dest)
  before = read_cells(dest)
  assert sorted(merge(dest, src)) == sorted(read_cells(src)) and all(cid.startswith("h/") for cid in read_cells(src))
  spec = load_study(os.path.join(dest, "study.yaml"))
  assert [g.name for g in spec.groups] == ["g", "h"] and spec.baselines == ("zero",)
  now = read_cells(dest)
  assert {cid: now[cid] for cid in before} == before and all(now[cid]["status"] == "done" for cid in read_cells(src))
  rows = final_table(load_results(dest))
  assert sum(r.startswith("| h |") for r in rows) == 2 and sum(r.startswith("| g |") for r in rows) == 2
  other = str(tmp_path / "other")
  shutil.copytree(src, other)
  changed = {**STUDY, "groups": [{**STUDY["groups"][0], "steps": [300]}, new_group], "baselines": []}
  yaml.safe_dump(changed, open(os.path.join(other, "study.yaml"), "w"), sort_keys=False)
  fresh = str(tmp_path / "fresh")
  shutil.copytree(finished, fresh)
  assert merge_main([fresh, other]) == 2
  assert "group 'g' differs" in capsys.readouterr().err
  assert load_study(os.path.join(fresh, "study.yaml")) == load_study(os.path.join(finished, "study.yaml"))

"""Merging a run's database that came back from a study worker into the study's database."""

from train.db import ExperimentDB


def _run_db(path, run_id="r1"):
  db = ExperimentDB(path)
  db.start(run_id, "asc-inc-cog", "ppo", "cpu", 0, {"a": 1}, "/worker/scratch/run", 512)
  db.log_stats(run_id, {"step": 256, "return_mean": 0.5, "source": "train"}, {"x": 1.0})
  db.log_evals(run_id, [{"scene": "hardest", "trial": t, "success": 1} for t in range(3)])
  db.finish(run_id, "done", {"step": 512}, 512)
  return db


def test_import_copies_every_row_once_and_points_at_the_local_folder(tmp_path):
  src = _run_db(str(tmp_path / "run.sqlite"))
  study = ExperimentDB(str(tmp_path / "study.sqlite"))
  for _ in range(2):  # a run that comes back twice (a retry) replaces its rows
    assert study.import_runs(src.path, str(tmp_path / "runs" / "r1")) == ["r1"]
  run = study.run("r1")
  assert run["status"] == "done" and run["out_dir"] == str(tmp_path / "runs" / "r1")
  assert [s["step"] for s in study.stats("r1")] == [256] and len(study.evals("r1")) == 3
  assert [e["event"] for e in study.events("r1")] == [e["event"] for e in src.events("r1")] == ["started", "finished"]
  _run_db(str(tmp_path / "other.sqlite"), "r2")
  study.import_runs(str(tmp_path / "other.sqlite"))
  assert [r["run_id"] for r in study.runs()] == ["r1", "r2"]

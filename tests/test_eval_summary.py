"""scripts/analysis/eval_summary.py: a run's reports in one table, their figures unchanged."""

import json
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "scripts", "analysis"))
from eval_summary import main  # noqa: E402


def _report(folder, scene, success, trials=4, budget=None, name=None):
  per_trial = [1.0] * round(success * trials) + [0.0] * (trials - round(success * trials))
  report = {"scene": scene, "budget": budget, "trials": trials, "command": f"python -m train.evaluate RUN --scene {scene}",
            "device": "cpu:0", "date": "2026-11-26T00:00:00+00:00", "per_trial": {"success": per_trial},
            "metrics": {"success": {"mean": sum(per_trial) / trials, "std": 0.0}, "progress": {"mean": 0.5, "std": 0.1}}}
  name = name or scene.replace("/", "-") + (f"@{budget}" if budget else "")
  (folder / f"eval-{name}.json").write_text(json.dumps(report))


def test_each_report_becomes_one_row_of_its_run_with_the_report_s_means(tmp_path, capsys):
  runs = []
  for seed, successes in ((0, {"hardest": 0.75, "hardest/rails": 0.0}), (1, {"hardest": 0.5})):
    run = tmp_path / f"s{seed}"
    run.mkdir()
    (run / "run.json").write_text(json.dumps({"run_id": f"r{seed}", "task": "t", "algo": "ppo", "seed": seed,
                                               "total_steps": 100, "config": {"huge": 1}}))
    for scene, success in successes.items():
      _report(run, scene, success)
    runs.append(str(run))
  _report(tmp_path / "s0", "hardest", 0.25, budget=50)  # a milestone's policy on the same scene: a row of its own
  _report(tmp_path / "s1", "hardest", 1.0, trials=2, name="hardest.2-trials")  # a shorter evaluation beside it
  _report(tmp_path / "s1", "uniform", 0.5, name="uniform")
  _report(tmp_path / "s1", "uniform", 0.75, name="uniform-again")  # as many trials: named by its file
  out = tmp_path / "summary.json"
  assert main([*runs, "--out", str(out)]) == 0
  got = json.loads(out.read_text())
  assert [(r["folder"], r["seed"]) for r in got["runs"]] == [("s0", 0), ("s1", 1)] and "config" not in got["runs"][0]
  assert got["runs"][0]["scenes"]["hardest"]["success"] == 0.75 and got["runs"][0]["scenes"]["hardest/rails"]["success"] == 0.0
  assert got["runs"][0]["scenes"]["hardest@50"]["success"] == 0.25
  assert got["runs"][1]["scenes"]["hardest (2 trials)"]["success"] == 1.0
  assert {k: v["success"] for k, v in got["runs"][1]["scenes"].items() if k.startswith("uniform")} == {
      "uniform": 0.75, "uniform (eval-uniform.json)": 0.5}  # the first by file name keeps the scene's name
  assert got["runs"][1]["scenes"]["hardest"] == {"file": "eval-hardest.json", "trials": 4, "command": "python -m train.evaluate RUN --scene hardest",
                                                 "device": "cpu:0", "date": "2026-11-26T00:00:00+00:00",
                                                 "success": 0.5, "progress": 0.5}
  assert got["made_by"].startswith("python scripts/analysis/eval_summary.py ") and "7 reports" in capsys.readouterr().out


def test_a_run_without_reports_is_refused_in_one_line(tmp_path, capsys):
  (tmp_path / "run.json").write_text(json.dumps({"run_id": "r"}))
  assert main([str(tmp_path), "--out", str(tmp_path / "x.json")]) == 2
  err = capsys.readouterr().err
  assert err.count("\n") == 1 and "no eval-*.json report" in err and not (tmp_path / "x.json").exists()
  _report(tmp_path, "hardest", 0.5)
  assert main([str(tmp_path), "--out", str(tmp_path / "no-such-folder" / "x.json")]) == 2  # one line, no traceback
  assert capsys.readouterr().err.startswith("error: ")

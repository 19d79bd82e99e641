"""scripts/analysis/harsh_grid_table.py against hand-made reports: grouping by task, policy kind
(algorithm or baseline) and case; the IQM of five seeds (the mean of the middle three); its
refusal of a folder without reports."""

import json
import os
import sys

import pytest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "scripts", "analysis"))
from harsh_grid_table import main, read_reports, table  # noqa: E402


def _report(folder, name, run_id, algo, case, success, trials=100):
  os.makedirs(folder / name, exist_ok=True)
  (folder / name / "run.json").write_text(json.dumps(
      {"run_id": run_id, "task": "asc-inc-cog", "algo": algo, "preset": "full" if algo == "baseline" else "gpu",
       "config": {}}))
  body = {"run_id": run_id, "task": "asc-inc-cog", "algo": algo, "scene": f"hardest+{case}", "trials": trials,
          "metrics": {"success": {"mean": success, "std": 0.0}}, "device": "cpu:0"}
  (folder / name / f"eval-hardest+{case}.json").write_text(json.dumps(body))


def test_seeds_group_into_one_row_per_case_with_the_iqm_of_their_middle_three(tmp_path):
  for seed, s in enumerate([0.1, 0.5, 0.6, 0.7, 1.0]):  # IQM of 5: drop one each side, mean of 0.5, 0.6, 0.7
    _report(tmp_path, f"ppo_s{seed}", f"ppo-{seed}", "ppo", "friction-0.7", s)
    _report(tmp_path, f"ppo_s{seed}", f"ppo-{seed}", "ppo", "mass-minus-30", 1.0)
  _report(tmp_path, "full-asc-inc-cog", "asc-inc-cog-baseline-full-3067ac", "baseline", "friction-0.7", 0.0)
  reports = read_reports(str(tmp_path))
  assert sorted(reports) == [("asc-inc-cog", "baseline-full", "friction-0.7"), ("asc-inc-cog", "ppo/gpu", "friction-0.7"),
                             ("asc-inc-cog", "ppo/gpu", "mass-minus-30")]
  rows = {(r["policy"], r["case"]): r for r in table(reports)}
  friction = rows[("ppo/gpu", "friction-0.7")]
  assert friction["runs"] == 5 and friction["success_iqm"] == pytest.approx(0.6)
  assert friction["ci95"][0] <= 0.6 <= friction["ci95"][1] and (friction["success_min"], friction["success_max"]) == (0.1, 1.0)
  assert rows[("ppo/gpu", "mass-minus-30")]["success_iqm"] == 1.0 and rows[("baseline-full", "friction-0.7")]["runs"] == 1


def test_a_folder_without_reports_is_refused_in_one_line(tmp_path, capsys):
  (tmp_path / "empty-run").mkdir()
  assert main([str(tmp_path)]) == 2
  assert "no eval-hardest+CASE.json reports" in capsys.readouterr().err

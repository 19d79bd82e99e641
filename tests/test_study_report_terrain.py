"""The study report of terrain tasks: per-kind hardest rows, and the mixed-terrain policy on each
kind's hardest configuration beside the specialists (IQM over seeds, from made-up trials)."""

from train.study.report import final_table, generalization_table, report_text, suite_table
from train.study.results import RunResult, StudyResults
from train.study.spec import cells, study_from_dict

SPEC = study_from_dict({"name": "t", "tasks": ["mixed-terrain", "uplift", "waves"], "seeds": [0, 1, 2],
                        "groups": [{"name": "ppo", "algo": "ppo", "preset": "cpu", "steps": [100]}],
                        "baselines": []})
SUCCESS = {("mixed-terrain", "hardest/uplift"): 1, ("mixed-terrain", "hardest/waves"): 0,
           ("uplift", "hardest"): 0, ("waves", "hardest"): 1}  # every trial of every seed


def _results() -> StudyResults:
  runs = []
  for c in cells(SPEC):
    evals = [{"scene": scene, "budget": None, "trial": i, "success": ok, "progress": ok, "cog_deviation": 0.0,
              "pitch_rate": 0.1, "tipped_over": 0, "collided": 1 - ok} for (task, scene), ok in SUCCESS.items() if task == c.task
             for i in range(4)]
    runs.append(RunResult(c, f"{c.task}-{c.seed}", [], evals))
  return StudyResults(SPEC, "/nowhere/t", runs, {c.id: {"status": "done", "attempts": []} for c in cells(SPEC)})


def test_the_mixed_policy_sits_beside_each_kinds_specialist():
  rows = generalization_table(_results())
  uplift = next(r for r in rows if "| uplift |" in r)
  waves = next(r for r in rows if "| waves |" in r)
  assert "| 1.00 [1.00, 1.00] | uplift: 0.00 [0.00, 0.00] |" in uplift
  assert "| 0.00 [0.00, 0.00] | waves: 1.00 [1.00, 1.00] |" in waves
  assert len(rows) == 2 + 8  # header, and each kind of the mixed task (kinds without a specialist: -)
  assert sum(r.endswith("| - |") for r in rows) == 6


def test_per_kind_hardest_rows_runs_counted_on_any_scene_and_no_figure_9_without_the_papers_tasks():
  rows = suite_table(_results())
  assert rows[2:] == ["| ppo | mixed-terrain | 100 | hardest/uplift | 3 | 1.00 [1.00, 1.00] | 1.00 [1.00, 1.00] | 0.00 [0.00, 0.00] |",
                      "| ppo | mixed-terrain | 100 | hardest/waves | 3 | 0.00 [0.00, 0.00] | 0.00 [0.00, 0.00] | 1.00 [1.00, 1.00] |"]
  mixed = next(r for r in final_table(_results()) if "| mixed-terrain |" in r)
  assert mixed.startswith("| ppo | mixed-terrain | 100 | 3 | - | - | - |")  # no 'hardest' of its own here
  text = report_text(_results(), [], "cmd")
  assert "Generalization" in text and "Figure 9" not in text

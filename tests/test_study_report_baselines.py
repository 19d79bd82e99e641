"""Baselines in a study: one evaluation cell per baseline and task it can drive, and the report's
baseline table with the saturation verdict (from made-up trials)."""

import pytest

from mjx_tracks.baselines import SATURATED, saturated
from mjx_tracks.envs.config import ConfigError
from train.study.report import baseline_table, final_table, improvement_table
from train.study.results import RunResult, StudyResults
from train.study.spec import cells, study_from_dict

SPEC = study_from_dict({"name": "b", "tasks": ["asc-inc-cog", "des-inc-ang", "nav"], "seeds": [3, 4],
                        "groups": [{"name": "ppo", "algo": "ppo", "preset": "cpu", "steps": [100]}],
                        "compare": [["asc-inc-cog", "des-inc-ang"]]})
# (task, policy) -> success per trial on the hardest scene (nav has none); every trial's pitch rate 0.3
SUCCESS = {("asc-inc-cog", "full"): [1, 1, 1, 1], ("asc-inc-cog", "zero"): [0, 0, 0, 1],
           ("des-inc-ang", "full"): [1, 0, 1, 0], ("des-inc-ang", "zero"): [1, 1, 1, 0], ("asc-inc-cog", "ppo"): [1] * 4,
           ("des-inc-ang", "ppo"): [1] * 4}


def _results() -> StudyResults:
  runs = []
  for c in cells(SPEC):
    policy = c.preset if c.is_baseline else c.group
    trials = SUCCESS.get((c.task, policy), [])
    evals = [{"scene": "hardest", "budget": None, "trial": i, "success": ok, "progress": 0.5 + ok / 2,
              "cog_deviation": 0.1, "pitch_rate": 0.3 if c.is_baseline else 0.2, "tipped_over": 0}
             for i, ok in enumerate(trials)]
    runs.append(RunResult(c, f"{c.id}", [], evals))
  return StudyResults(SPEC, "/nowhere/b", runs, {c.id: {"status": "done", "attempts": []} for c in cells(SPEC)})


def test_each_baseline_is_one_evaluation_per_task_it_can_drive():
  base = [c for c in cells(SPEC) if c.is_baseline]
  # the stair script drives stair tasks only; zero, full and random drive every task
  assert sorted((c.task, c.preset) for c in base) == sorted(
      [(t, b) for t in ("asc-inc-cog", "des-inc-ang") for b in ("zero", "full", "random", "scripted")] +
      [("nav", b) for b in ("zero", "full", "random")])
  assert all(c.seed == 3 and c.steps == 0 and c.group == f"baseline-{c.preset}" for c in base)
  assert base[0].eval_args(100) == ["--baseline", base[0].preset, "--task", base[0].task, "--suite", "--trials", "100"]
  assert not [c for c in cells(study_from_dict({**_raw(), "baselines": []})) if c.is_baseline]
  with pytest.raises(ConfigError, match="baselines"):
    study_from_dict({**_raw(), "baselines": ["zero", "best"]})


def _raw() -> dict:
  return {"name": "b", "tasks": ["asc-inc-cog"], "seeds": [0],
          "groups": [{"name": "ppo", "algo": "ppo", "preset": "cpu", "steps": [100]}]}


def test_the_report_marks_a_task_saturated_when_a_constant_baseline_passes_its_hardest_scene():
  rows = baseline_table(_results())
  asc = [r for r in rows if r.startswith("| asc-inc-cog |")]
  assert asc[0] == "| asc-inc-cog | baseline zero | 0.250 | 0.625 | 0.300 | 0.100 |"
  assert asc[1] == "| asc-inc-cog | baseline full | 1.000 | 1.000 | 0.300 | 0.100 |"
  assert asc[2] == "| asc-inc-cog | ppo @ 100 (mean of 2 seeds) | 1.000 | 1.000 | 0.200 | 0.100 |"
  assert asc[-1] == "| asc-inc-cog | **saturated** | | | | |"
  # full 0.5, zero 0.75: neither reaches SATURATED
  assert [r for r in rows if r.startswith("| des-inc-ang |")][-1] == "| des-inc-ang | **not saturated** | | | | |"
  assert not [r for r in rows if r.startswith("| nav |")]  # no hardest scene, no trials there
  assert saturated({"zero": SATURATED}) and not saturated({"random": 1.0, "full": SATURATED - 0.01})


def test_baselines_sit_in_the_final_table_but_not_in_the_comparisons_of_trained_groups():
  final = final_table(_results())
  assert any(r.startswith("| baseline-full | asc-inc-cog | - | 1 | 1.00 [1.00, 1.00] |") for r in final)
  assert not any("baseline" in r for r in improvement_table(_results()))


def test_the_final_figure_draws_each_baseline_beside_the_trained_policy():
  from train.study.figures import final_figure
  fig = final_figure(_results(), "ppo")
  hardest = fig.axes[0]
  assert hardest.get_title() == "hardest"
  lines = {c.get_label(): c for c in hardest.collections if c.get_label().startswith("baseline ")}
  assert set(lines) >= {"baseline zero", "baseline full"}  # labelled once, on the first task
  heights = sorted(float(seg[0][1]) for c in hardest.collections if c.get_label() != "_nolegend_"
                   for seg in c.get_segments() if len(seg) == 2 and seg[0][1] == seg[1][1])
  # zero 0.25 and full 1.0 on asc-inc-cog; zero 0.75 and full 0.5 on des-inc-ang (made-up trials above)
  assert {0.25, 0.5, 0.75, 1.0} <= set(heights)


def test_attempts_cut_off_by_a_stopped_study_are_counted_not_listed_as_failures():
  from types import SimpleNamespace

  from train.study.report import attempts_lines
  stopped = {"stopped": True, "rc": None, "worker": None, "phase": None, "error": "the study stopped during this attempt"}
  state = {"g/t/1/s0": {"status": "done", "attempts": [stopped, {"rc": 0, "worker": "cpu", "phase": "evaluate"}]},
           "g/t/1/s1": {"status": "failed", "attempts": [dict(stopped), {"rc": 1, "worker": "cpu", "phase": "train",
                                                                         "error": "Traceback\nValueError: boom"}]}}
  lines = attempts_lines(SimpleNamespace(state=state))
  assert lines[1].startswith("- 2 attempts were cut off by the study stopping")
  assert [line for line in lines if "` attempt" in line] == ["- `g/t/1/s1` attempt 2 on cpu: rc 1, train: ValueError: boom"]

"""The report's "paper's evaluation" table: each seed's first 10 trials (by trial index) on the
hardest staircase, the paper's figure of the task (ascent progress, descent pitch rate), from
made-up trials whose means and standard deviations are known by hand."""

import numpy as np

import pytest

from train.study.paper import FIGURE9, JUDGED_BY, PAPER_TRIALS, paper_figure
from train.study.report import paper_trials_table
from train.study.results import RunResult, StudyResults
from train.study.spec import cells, study_from_dict

SPEC = study_from_dict({"name": "p", "tasks": ["asc-inc-cog", "des-inc-ang", "nav"], "seeds": [3, 4], "baselines": [],
                        "groups": [{"name": "sac", "algo": "sac", "preset": "paper", "steps": [100]}]})


def _trials(c) -> list[dict]:
  if c.seed == 4 and c.task == "des-inc-ang":
    n = PAPER_TRIALS - 1  # too few for the paper's evaluation: left out
  else:
    n = 12
  # stored out of order; by index: trials 0-4 progress 0.2, 5-9 0.6, 10-11 1.0 (not among the first 10)
  order = list(range(n))[::-1]
  other = [{"scene": "uniform", "budget": None, "trial": i, "progress": 0.0, "pitch_rate": 9.0} for i in range(12)]
  other += [{"scene": "hardest", "budget": 50, "trial": i, "progress": 0.0, "pitch_rate": 9.0} for i in range(12)]
  return other + [{"scene": "hardest", "budget": None, "trial": i, "progress": 0.2 if i < 5 else (0.6 if i < 10 else 1.0),
                   "pitch_rate": 0.1 * (i % 2) + 0.3, "success": 0} for i in order]


def _results() -> StudyResults:
  runs = [RunResult(c, c.id, [], _trials(c)) for c in cells(SPEC)]
  return StudyResults(SPEC, "/nowhere/p", runs, {c.id: {"status": "done", "attempts": []} for c in cells(SPEC)})


def test_each_seed_reads_its_first_ten_trials_by_index():
  got = _results().first_trials("sac", "asc-inc-cog", 100, "hardest", "progress", PAPER_TRIALS)
  assert [s for s, _ in got] == [3, 4]
  np.testing.assert_allclose(got[0][1], [0.2] * 5 + [0.6] * 5)  # trials 10 and 11 (1.0) left out
  assert _results().first_trials("sac", "des-inc-ang", 100, "hardest", "pitch_rate", PAPER_TRIALS)[0][0] == 3


def test_the_table_gives_the_papers_figure_per_task_and_each_seeds_mean_and_sd():
  assert paper_figure("asc-inc-cog") == "progress" and paper_figure("des-uni-ang") == "pitch_rate"
  rows = paper_trials_table(_results())
  assert rows[2] == "| asc-inc-cog | progress | paper (Figure 9, one policy) | 0.965 +- 0.05 |"
  # mean 0.4, population sd 0.2 (half the trials 0.2, half 0.6)
  assert rows[3] == "| asc-inc-cog | progress | sac @ 100 | s3 0.40 +- 0.20, s4 0.40 +- 0.20 |"
  # pitch rate alternates 0.3 / 0.4: mean 0.35, sd 0.05; seed 4 has 9 trials, so only seed 3
  assert rows[5] == "| des-inc-ang | pitch rate | sac @ 100 | s3 0.35 +- 0.05 |"
  assert len(rows) == 6  # nav: not one of the paper's tasks
  assert paper_trials_table(StudyResults(SPEC, "/nowhere/p", [], {})) == []  # no seed with 10 trials: no table


def test_each_task_of_figure_9_is_judged_by_one_of_its_figures_and_a_repeated_trial_is_refused():
  assert JUDGED_BY.keys() == FIGURE9.keys() and all(JUDGED_BY[t] in FIGURE9[t] for t in FIGURE9)
  r = _results()
  twice = RunResult(r.runs[0].cell, "twice", [], r.runs[0].evals + r.runs[0].evals[-1:])
  with pytest.raises(ValueError, match="trial index twice"):
    StudyResults(SPEC, "/nowhere/p", [twice], r.state).first_trials("sac", "asc-inc-cog", 100, "hardest", "progress", 10)

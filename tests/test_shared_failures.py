"""scripts/analysis/shared_failures.py: failures spread over trials at random give the count variance of
independent policies; failures gathered on a few trials give more, and the trials nobody climbs."""

import os
import sqlite3
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "scripts", "analysis"))
from shared_failures import successes, summary  # noqa: E402


def _table(m: np.ndarray) -> dict:
  return {f"r{i}": {t: float(x) for t, x in enumerate(row)} for i, row in enumerate(m)}


def test_independent_failures_match_the_poisson_binomial_variance_and_shared_ones_exceed_it():
  rng = np.random.default_rng(0)
  rates = rng.uniform(0.6, 0.9, 40)
  independent = summary(_table(rng.random((40, 4000)) < rates[:, None]))
  assert independent["count_variance_observed"] == pytest.approx(independent["count_variance_if_trial_independent"],
                                                                 rel=0.1)
  hard = rng.random(4000) < 0.25  # a quarter of the trials fail for every policy, the rest never
  shared = summary(_table(np.tile(~hard, (40, 1))))
  # every policy alike: the count is 0 or 40, variance 40^2 x 0.25 x 0.75 = 300 against 40 x 0.25 x 0.75
  assert shared["count_variance_observed"] > 10 * shared["count_variance_if_trial_independent"]
  assert shared["trials_climbed_by_none"] == hard.sum()
  assert sum(shared["policies_climbing_a_trial_histogram"]) == 4000


def test_the_database_reader_keeps_the_task_and_its_variants_and_leaves_baselines_out(tmp_path):
  db = str(tmp_path / "study.sqlite")
  with sqlite3.connect(db) as c:
    c.execute("CREATE TABLE experiments (run_id TEXT, task TEXT, algo TEXT)")
    c.execute("CREATE TABLE evals (run_id TEXT, scene TEXT, trial INTEGER, success REAL)")
    runs = [("a", "asc-inc-cog", "ppo"), ("b", "asc-inc-cog-robust", "ppo"), ("c", "asc-inc-cog", "baseline"),
            ("d", "asc-uni-cog", "ppo")]
    c.executemany("INSERT INTO experiments VALUES (?, ?, ?)", runs)
    c.executemany("INSERT INTO evals VALUES (?, 'hardest+friction-low', 0, ?)", [(r, 1.0) for r in "abcd"])
  assert sorted(successes([db], "hardest+friction-low", "asc-inc-cog")) == [f"{db}:a", f"{db}:b"]

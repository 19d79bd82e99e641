"""scripts/analysis/shared_failures.py: failures spread over trials at random give the count variance of
independent policies; failures gathered on a few trials give more, and the trials nobody climbs; runs
are compared only with runs whose scene config draws the same trials."""

import json
import os
import sqlite3
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "scripts", "analysis"))
from shared_failures import outcomes, summary  # noqa: E402

from mjx_tracks.envs.config import load_config  # noqa: E402


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
  assert shared["trials_of_no_policy"] == hard.sum() and shared["trials_of_every_policy"] == 4000 - hard.sum()
  assert sum(shared["policies_per_trial_histogram"]) == 4000


def _config_json(task: str, *overrides: str, drop: str | None = None) -> str:
  raw = load_config(task, list(overrides)).to_dict()
  if drop:  # a run recorded before this scene key existed
    del raw["scene"][drop]
  return json.dumps(raw)


def test_the_database_reader_keeps_the_task_and_its_variants_and_leaves_baselines_out(tmp_path):
  db = str(tmp_path / "study.sqlite")
  plain = _config_json("asc-inc-cog")
  with sqlite3.connect(db) as c:
    c.execute("CREATE TABLE experiments (run_id TEXT, task TEXT, algo TEXT, config_json TEXT)")
    c.execute("CREATE TABLE evals (run_id TEXT, scene TEXT, trial INTEGER, success REAL, collided REAL)")
    runs = [("a", "asc-inc-cog", "ppo", plain), ("b", "asc-inc-cog-robust", "ppo", plain),
            ("c", "asc-inc-cog", "baseline", plain), ("d", "asc-uni-cog", "ppo", plain),
            ("e", "asc-inc-cog", "ppo", _config_json("asc-inc-cog", drop="nav_length")),  # today's default fills it
            ("f", "asc-inc-cog", "ppo", _config_json("asc-inc-cog", "scene.riser=[0.1, 0.2]"))]  # other staircases
    c.executemany("INSERT INTO experiments VALUES (?, ?, ?, ?)", runs)
    c.executemany("INSERT INTO evals VALUES (?, 'hardest+friction-low', 0, ?, ?)", [(r[0], 1.0, 0.0) for r in runs])
  families = outcomes([db], "hardest+friction-low", "asc-inc-cog")
  assert sorted(sorted(t) for t in families.values()) == [[f"{db}:a", f"{db}:b", f"{db}:e"], [f"{db}:f"]]
  collided = outcomes([db], "hardest+friction-low", "asc-inc-cog", "collided")
  assert {r: t[0] for table in collided.values() for r, t in table.items()} == {f"{db}:{r}": 0.0 for r in "abef"}
  with pytest.raises(ValueError, match="outcome"):
    outcomes([db], "hardest+friction-low", "asc-inc-cog", "success; DROP TABLE evals")
  with pytest.raises(FileNotFoundError, match="no such study database"):  # not a new empty file
    outcomes([str(tmp_path / "missing.sqlite")], "hardest+friction-low", "asc-inc-cog")
  assert not (tmp_path / "missing.sqlite").exists()


def test_only_the_trials_every_policy_ran_are_compared_and_the_others_counted():
  s = summary({"a": {0: 1.0, 1: 0.0, 2: 1.0, 3: 1.0}, "b": {0: 1.0, 1: 1.0, 2: 0.0}})
  assert s["trials"] == 3 and s["trials_not_every_policy_ran"] == 1
  assert s["policies_per_trial_histogram"] == [0, 2, 1]  # trial 0 both, trials 1 and 2 one each

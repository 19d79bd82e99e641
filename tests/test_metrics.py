"""The metrics schema (mjx_tracks.metrics) against plain-Python figures, and its readers."""

import sqlite3

import numpy as np
import pytest

from mjx_tracks.metrics import (EPISODE_NAMES, REPORT_COLUMN, STEP_NAMES, episode_figures, trajectory_success,
                                trial_row)


def test_episode_figures_match_a_hand_computation():
  # two episodes: 4 steps, 3 on the stairs, reached; 10 steps, never on the stairs, tipped over
  sums = {k: np.zeros(2) for k in STEP_NAMES}
  sums["progress"][:] = [1.0, 0.25]
  sums["on_stairs"][:] = [3, 0]
  sums["cog_deviation"][:] = [0.3, 0.0]
  sums["pitch_rate"][:] = [2.0, 5.0]
  sums["goal_reached"][:] = [1, 0]
  sums["tipped_over"][:] = [0, 1]
  fig = episode_figures(sums, np.array([4, 10]))
  assert tuple(fig) == EPISODE_NAMES
  np.testing.assert_allclose(fig["cog_deviation"], [0.1, 0.0])  # m, mean while on the stairs
  np.testing.assert_allclose(fig["pitch_rate"], [0.5, 0.5])  # rad/s, per step
  assert fig["success"].tolist() == [1.0, 0.0] and fig["tipped_over"].tolist() == [0.0, 1.0]
  row = trial_row(fig, 0)
  assert row == pytest.approx({"progress": 1.0, "success": 1, "cog_deviation": 0.1, "pitch_rate": 0.5,
                               "tipped_over": 0, "length": 4})
  assert [type(row[k]) for k in ("success", "tipped_over", "length")] == [int] * 3


def test_a_trajectory_succeeds_as_an_episode_would():
  assert trajectory_success([0, 0, 1], [0, 0, 0])
  assert not trajectory_success([0, 0, 1], [0, 1, 0])  # tipped first: the episode ended there
  assert trajectory_success([0, 1, 0], [0, 1, 1])  # both on one step: the goal counts
  assert not trajectory_success([0, 0], [0, 0])


def test_the_database_columns_are_the_schemas(tmp_path):
  from train.db import ExperimentDB
  db = ExperimentDB(str(tmp_path / "x.sqlite"))
  with sqlite3.connect(db.path) as c:
    cols = lambda t: [r[1] for r in c.execute(f"PRAGMA table_info({t})")]  # noqa: E731
    assert set(EPISODE_NAMES) <= set(cols("evals")) and set(REPORT_COLUMN.values()) <= set(cols("stats"))

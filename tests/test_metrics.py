"""The metrics schema (mjx_tracks.metrics) against plain-Python figures, and its readers."""

import sqlite3

import numpy as np
import pytest

from mjx_tracks.metrics import (EPISODE_NAMES, REPORT_COLUMN, STEP_NAMES, episode_figures, timed_out,
                                trajectory_success, trial_row)


def test_episode_figures_match_a_hand_computation():
  # two episodes: 4 steps, 3 on the stairs, reached; 10 steps, never on the stairs, touched walls at
  # 2 steps, tipped over
  sums = {k: np.zeros(2) for k in STEP_NAMES}
  sums["progress"][:] = [1.0, 0.25]
  sums["on_stairs"][:] = [3, 0]
  sums["cog_deviation"][:] = [0.3, 0.0]
  sums["pitch_rate"][:] = [2.0, 5.0]
  sums["goal_reached"][:] = [1, 0]
  sums["tipped_over"][:] = [0, 1]
  sums["collision"][:] = [0, 2]
  sums["command_filtered"][:] = [1, 0]
  fig = episode_figures(sums, np.array([4, 10]))
  assert tuple(fig) == EPISODE_NAMES
  np.testing.assert_allclose(fig["cog_deviation"], [0.1, 0.0])  # m, mean while on the stairs
  np.testing.assert_allclose(fig["pitch_rate"], [0.5, 0.5])  # rad/s, per step
  assert fig["success"].tolist() == [1.0, 0.0] and fig["tipped_over"].tolist() == [0.0, 1.0]
  assert fig["collided"].tolist() == [0.0, 1.0]  # a rate of episodes, not of steps
  assert fig["filtered"].tolist() == [0.25, 0.0]  # a fraction of the episode's steps
  row = trial_row(fig, 0)
  assert row == pytest.approx({"progress": 1.0, "success": 1, "cog_deviation": 0.1, "pitch_rate": 0.5,
                               "tipped_over": 0, "length": 4, "collided": 0, "filtered": 0.25})
  assert [type(row[k]) for k in ("success", "tipped_over", "length", "collided")] == [int] * 4
  assert trial_row(fig, 1)["length"] == 10 and trial_row(fig, 1)["collided"] == 1


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


def test_a_database_from_before_a_metric_existed_gains_its_column(tmp_path):
  """An evals / stats table without the collision columns (as databases written before them)."""
  from train.db import ExperimentDB
  path = tmp_path / "old.sqlite"
  with sqlite3.connect(path) as c:
    c.execute("CREATE TABLE evals (run_id TEXT NOT NULL, scene TEXT NOT NULL, trial INTEGER NOT NULL, "
              "progress REAL, success INTEGER, created TEXT)")
    c.execute("CREATE TABLE stats (run_id TEXT NOT NULL, step INTEGER NOT NULL, success_rate REAL)")
    c.execute("INSERT INTO evals (run_id, scene, trial, progress, success) VALUES ('r', 'uniform', 0, 0.5, 0)")
  ExperimentDB(str(path))
  with sqlite3.connect(path) as c:
    cols = lambda t: [r[1] for r in c.execute(f"PRAGMA table_info({t})")]  # noqa: E731
    assert {"collided", "length", "budget"} <= set(cols("evals")) and "collision_rate" in cols("stats")
    assert c.execute("SELECT progress, collided FROM evals").fetchone() == (0.5, None)


def test_a_trial_timed_out_where_it_neither_reached_collided_nor_tipped():
  # four trials: reached; collided (and went on); tipped over; none of these
  figures = {"success": [1.0, 0.0, 0.0, 0.0], "collided": [0.0, 1.0, 0.0, 0.0], "tipped_over": [0.0, 0.0, 1.0, 0.0]}
  assert timed_out(figures).tolist() == [False, False, False, True]

"""The study report's statistics against rliable's own functions: the interquartile mean it
computes per bootstrap resample equals rliable's aggregate_iqm bit for bit, so the intervals do."""

import numpy as np
from rliable import library as rly, metrics

from train.study import statistics


def test_the_iqm_is_rliables_bit_for_bit_for_any_number_of_runs():
  rng = np.random.default_rng(7)
  for n in range(1, 41):
    for scores in (rng.random((n, 1)), rng.integers(0, 101, (n, 1)) / 100, rng.normal(0, 1e6, (n, 1))):
      assert statistics.iqm(scores) == metrics.aggregate_iqm(scores), n
  cut_mid = np.array([[0.0], [1.0], [2.0], [100.0]])  # one score cut at each end: the mean of 1 and 2
  assert statistics.iqm(cut_mid) == 1.5


def test_the_intervals_are_rliables_with_its_own_iqm():
  rng = np.random.default_rng(3)
  scores = {"a": rng.random(5), "b": rng.integers(0, 101, 7) / 100, "one run": np.array([0.4])}
  got = statistics.iqm_intervals(scores, reps=300)
  np.random.seed(statistics.SEED)
  point, ci = rly.get_interval_estimates({k: v.reshape(-1, 1) for k, v in scores.items()},
                                         lambda x: np.array([metrics.aggregate_iqm(x)]), reps=300,
                                         confidence_interval_size=statistics.LEVEL)
  assert got == {k: (float(point[k][0]), float(ci[k][0, 0]), float(ci[k][1, 0])) for k in scores}
  assert got["a"][1] < got["a"][0] < got["a"][2]  # a real interval around the point


def test_the_probability_of_improvement_is_rliables_bit_for_bit():
  rng = np.random.default_rng(11)
  for nx, ny, tasks in ((1, 1, 1), (5, 5, 1), (3, 7, 1), (5, 4, 3), (10, 10, 2)):
    for draw in (lambda n: rng.random((n, tasks)), lambda n: rng.integers(0, 4, (n, tasks)) / 4.0):  # with ties
      x, y = draw(nx), draw(ny)
      assert statistics.probability_of_improvement(x, y) == metrics.probability_of_improvement(x, y), (nx, ny, tasks)
  same = rng.random((4, 2))
  assert statistics.probability_of_improvement(same, same) == metrics.probability_of_improvement(same, same) == 0.5
  above, below = np.array([[3.0], [4.0]]), np.array([[1.0], [3.0]])  # pairs: 3>1, 3=3 (half), 4>1, 4>3
  assert statistics.probability_of_improvement(above, below) == 3.5 / 4
  with_nan = np.array([[np.nan], [1.0]])
  assert np.isnan(statistics.probability_of_improvement(with_nan, below))
  assert np.isnan(metrics.probability_of_improvement(with_nan, below))

"""Statistics of a study's runs: interquartile mean with stratified bootstrap 95 % confidence
intervals and the probability of improvement (both through rliable), and bootstrap bands of mean
learning curves."""

from __future__ import annotations

import numpy as np

REPS = 2000  # bootstrap resamples
LEVEL = 0.95  # confidence level of every interval
SEED = 0  # bootstrap RNG seed: a report is reproducible


def iqm_intervals(scores: dict[str, np.ndarray], reps: int = REPS) -> dict[str, tuple[float, float, float]]:
  """{label: (IQM, low, high)} over runs; scores[label] holds one figure per run (seed)."""
  from rliable import library as rly  # noqa: PLC0415
  np.random.seed(SEED)  # rliable's bootstrap draws from NumPy's global generator
  matrices = {k: np.asarray(v, float).reshape(-1, 1) for k, v in scores.items() if len(v)}
  if not matrices:
    return {}
  point, ci = rly.get_interval_estimates(matrices, lambda x: np.array([iqm(x)]),
                                         reps=reps, confidence_interval_size=LEVEL)
  return {k: (float(point[k][0]), float(ci[k][0, 0]), float(ci[k][1, 0])) for k in matrices}


def iqm(scores: np.ndarray) -> float:
  """The interquartile mean of all the scores: rliable's `metrics.aggregate_iqm`, which is
  `scipy.stats.trim_mean(scores, 0.25, axis=None)` (a quarter of the scores cut at each end, the
  count rounded down), computed as scipy does (a partition, then the mean of the middle) but
  without scipy's ~0.2 ms of argument handling per call: a study's report computes it ~100,000
  times in its bootstraps (tests/test_study_statistics.py checks it equals rliable's, bit for bit)."""
  a = np.ravel(np.asarray(scores, float))
  cut = int(0.25 * a.size)
  return float(np.mean(np.partition(a, (cut, a.size - cut - 1))[cut:a.size - cut]))


def improvement(pairs: dict[str, tuple[np.ndarray, np.ndarray]],
                reps: int = REPS) -> dict[str, tuple[float, float, float]]:
  """{label: (P(X > Y), low, high)}: the probability that a run of X scores above one of Y
  (ties count half), over the runs of each, with its bootstrap interval."""
  from rliable import library as rly  # noqa: PLC0415
  np.random.seed(SEED)
  given = {k: (np.asarray(x, float).reshape(-1, 1), np.asarray(y, float).reshape(-1, 1))
           for k, (x, y) in pairs.items() if len(x) and len(y)}
  if not given:
    return {}
  point, ci = rly.get_interval_estimates(given, probability_of_improvement, reps=reps,
                                         confidence_interval_size=LEVEL)
  return {k: (float(np.squeeze(point[k])), float(np.squeeze(ci[k][0])), float(np.squeeze(ci[k][1])))
          for k in given}


def probability_of_improvement(scores_x: np.ndarray, scores_y: np.ndarray) -> float:
  """rliable's `metrics.probability_of_improvement` (runs x tasks matrices), computed alike without
  scipy's per-call overhead: per task, the Mann-Whitney U statistic of X over Y (the pairs of runs
  where X scores above Y, ties counting half) over the number of pairs, or 0.5 where the two
  columns are equal (a NaN score makes the task's NaN, as scipy's); the mean over tasks."""
  per_task = []
  for a, b in zip(np.asarray(scores_x, float).T, np.asarray(scores_y, float).T):
    if np.array_equal(a, b):
      per_task.append(0.5)
    elif np.isnan(a).any() or np.isnan(b).any():
      per_task.append(np.nan)
    else:
      above, tied = np.count_nonzero(a[:, None] > b[None, :]), np.count_nonzero(a[:, None] == b[None, :])
      per_task.append((above + 0.5 * tied) / (a.size * b.size))
  return float(np.mean(per_task))


def curve_band(curves: list[tuple[np.ndarray, np.ndarray]], points: int = 50,
               reps: int = REPS) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
  """(x, mean, low, high): the runs' curves interpolated on a common grid up to the shortest run's
  end, their mean and its percentile bootstrap band (runs resampled with replacement)."""
  end = min(x[-1] for x, _ in curves)
  start = max(x[0] for x, _ in curves)
  grid = np.linspace(start, end, points) if end > start else np.array([end])
  ys = np.stack([np.interp(grid, x, y) for x, y in curves])  # (runs, points)
  rng = np.random.default_rng(SEED)
  idx = rng.integers(0, len(ys), size=(reps, len(ys)))
  means = ys[idx].mean(axis=1)  # (reps, points)
  tail = (1 - LEVEL) / 2 * 100
  return grid, ys.mean(axis=0), np.percentile(means, tail, axis=0), np.percentile(means, 100 - tail, axis=0)

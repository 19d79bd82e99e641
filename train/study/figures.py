"""The study report's figures (matplotlib, PNG): learning curves per group with bootstrap bands,
against environment steps and wall time, and final success per budget with IQM intervals and each
baseline's figure beside them."""

from __future__ import annotations

import os

import numpy as np

from mjx_tracks.metrics import BY_NAME, REPORT_COLUMN
from train.study.results import CURVE_METRICS, StudyResults
from train.study.statistics import curve_band, iqm_intervals

X_AXES = {"step": "environment steps", "wall_s": "wall time (s)"}
# a report column's axis label: its metric's name and unit (mjx_tracks.metrics.REPORT)
LABELS = {"return_mean": "return", "eps": "eps", **{c: n.replace("_", " ") + (f" ({BY_NAME[n].unit})" if BY_NAME[n].unit else "")
                                                    for n, c in REPORT_COLUMN.items()}}


def _pyplot():
  """pyplot, on the backend matplotlib picks (Agg without a display; inline in a notebook)."""
  import matplotlib.pyplot as plt  # noqa: PLC0415
  return plt


def curves_figure(results: StudyResults, group: str, x: str):
  """One panel per training metric; a line per task: mean over runs with its 95 % bootstrap band."""
  plt = _pyplot()
  fig, axes = plt.subplots(2, 3, figsize=(13, 6.5), constrained_layout=True)
  for ax, metric in zip(axes.flat, CURVE_METRICS):
    for task in results.spec.tasks:
      runs = results.curves(group, task, x, metric)
      if not runs:
        continue
      grid, mean, lo, hi = curve_band(runs)
      line, = ax.plot(grid, mean, label=f"{task} ({len(runs)} runs)")
      ax.fill_between(grid, lo, hi, color=line.get_color(), alpha=0.2, linewidth=0)
    ax.set_xlabel(X_AXES[x])
    ax.set_ylabel(LABELS[metric])
    ax.grid(alpha=0.3)
  axes.flat[0].legend(fontsize=8)
  fig.suptitle(f"{group}: training episodes, mean and 95 % bootstrap band over seeds")
  return fig


COLUMNS = 4  # panels per row of the final figure
BASELINE_STYLES = ("--", ":", "-.", (0, (5, 1, 1, 1, 1, 1)))  # line styles of the baselines, in the spec's order
BASELINE_COLORS = ("0.35", "tab:red", "tab:purple", "tab:green")  # with one budget (each task has its place)


def _baseline_lines(ax, results: StudyResults, scene: str, metric: str, one_budget: bool) -> None:
  """Each baseline's figure on the scene as a horizontal line: with one budget across its task's
  point in the baseline's colour, else in the task's colour; labelled `baseline NAME` once a panel."""
  for i, task in enumerate(results.spec.tasks):
    for name, value in results.baseline_figure(task, scene, metric).items():
      k = results.spec.baselines.index(name)
      style = BASELINE_STYLES[k % len(BASELINE_STYLES)]
      label = f"baseline {name}" if i == 0 else None
      if one_budget:
        ax.hlines(value, i - 0.4, i + 0.4, colors=BASELINE_COLORS[k % len(BASELINE_COLORS)], linestyles=style,
                  label=label, alpha=0.8)
      else:
        ax.axhline(value, color=f"C{i % 10}", linestyle=style, label=label, alpha=0.6)


def _final_panel(ax, results: StudyResults, group: str, scene: str, metric: str, budgets: list[int]) -> None:
  """IQM [95 % CI] of metric over seeds per task: against the budget, or with one budget, per task."""
  one = len(budgets) == 1
  for i, task in enumerate(results.spec.tasks):
    est = iqm_intervals({str(b): results.final(group, task, b, scene, metric) for b in budgets})
    xs = [b for b in budgets if str(b) in est]
    if xs:
      mid = np.array([est[str(b)][0] for b in xs])
      err = np.array([[m - est[str(b)][1], est[str(b)][2] - m] for b, m in zip(xs, mid)]).T
      ax.errorbar([i] if one else xs, mid, yerr=err, marker="o", capsize=3, label=task, color=f"C{i % 10}")
  _baseline_lines(ax, results, scene, metric, one)
  if one:
    ax.set_xticks(range(len(results.spec.tasks)), results.spec.tasks, rotation=60, ha="right", fontsize=7)
    ax.set_xlim(-0.5, len(results.spec.tasks) - 0.5)
  else:
    ax.set_xscale("log")
    ax.set_xticks(budgets, [f"{b / 1e6:g}M" if b >= 100_000 else f"{b:,}" for b in budgets], minor=False)
    ax.minorticks_off()
    ax.set_xlabel("step budget")
  ax.set_title(scene, fontsize=10)
  ax.set_ylim(-0.05, 1.05)
  ax.grid(alpha=0.3)


def final_figure(results: StudyResults, group: str, metric: str = "success"):
  """One panel per evaluation scene (COLUMNS to a row): IQM of `metric` over seeds per budget, a
  line per task (one budget: a point per task)."""
  plt = _pyplot()
  scenes = results.scenes()
  rows, cols = -(-len(scenes) // COLUMNS), min(len(scenes), COLUMNS)
  fig, axes = plt.subplots(rows, cols, figsize=(3.6 * cols, 3.6 * rows), constrained_layout=True, squeeze=False)
  budgets = sorted({b for g, _, b in results.groups() if g == group})
  for ax, scene in zip(axes.flat, scenes):
    _final_panel(ax, results, group, scene, metric, budgets)
  for ax in axes.flat[len(scenes):]:
    ax.set_visible(False)
  axes[0][0].set_ylabel(f"{metric} (IQM, 95 % CI)")
  if len(budgets) > 1 or results.spec.baselines:
    axes[0][0].legend(fontsize=7)
  budget = "" if len(budgets) > 1 else f" at {budgets[0]:,} steps"
  fig.suptitle(f"{group}: {metric} per evaluation scene{budget} (evaluations of each run)")
  return fig


def write_figures(results: StudyResults, folder: str) -> list[str]:
  """Every figure of the report, as PNGs in `folder`; returns their file names."""
  plt = _pyplot()
  names = []
  for g in results.spec.groups:
    if not any(r.cell.group == g.name for r in results.runs):
      continue
    figs = {f"curves-{g.name}-{x}.png": curves_figure(results, g.name, x) for x in X_AXES}
    figs[f"final-{g.name}.png"] = final_figure(results, g.name)
    for name, fig in figs.items():
      fig.savefig(os.path.join(folder, name), dpi=110)
      plt.close(fig)
      names.append(name)
  return names

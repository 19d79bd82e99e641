"""Progress reporting: a status line per report, TensorBoard scalars, and database rows."""

from __future__ import annotations

import sys
import time
from typing import Any

import numpy as np

from mjx_tracks.metrics import REPORT_COLUMN, STEP_NAMES, episode_figures
from train.db import STAT_SOURCES
from train.core.probe import PREFIX as PROBE


def summarize(metrics: dict[str, Any]) -> dict[str, float]:
  """Report columns (mjx_tracks.metrics.REPORT) from Brax's training ('episode/...') or
  evaluation ('eval/episode_...') metrics: batch means of the episode sums, so the COG deviation
  and pitch rate are ratios of means, and the rates (success, tip-overs) the means of the
  episodes' 0/1 sums (an episode reaches the goal or tips over at most once: either ends it)."""
  m = {k: float(np.asarray(v)) for k, v in metrics.items() if np.asarray(v).size == 1}
  if any(k.startswith(PROBE) for k in m):  # already per-trial means (train.core.probe)
    return {k[len(PROBE):]: v for k, v in m.items() if k.startswith(PROBE)}
  if "episode/sum_reward" in m:
    prefix, ret, length = "episode/", m["episode/sum_reward"], m.get("episode/length")
  elif "eval/episode_reward" in m:
    prefix, ret, length = "eval/episode_", m["eval/episode_reward"], m.get("eval/avg_episode_length")
  else:
    return {}
  if any(f"{prefix}{k}" not in m for k in STEP_NAMES):
    return {"return_mean": ret}
  fig = episode_figures({k: m[f"{prefix}{k}"] for k in STEP_NAMES}, length if length else 1.0)
  fig.update(success=m[f"{prefix}goal_reached"], tipped_over=m[f"{prefix}tipped_over"],  # rates: means of 0/1 sums
             collided=m[f"{prefix}collision"])
  out = {"return_mean": ret, **{c: fig[n] for n, c in REPORT_COLUMN.items() if n != "pitch_rate" or length}}
  return {k: float(v) for k, v in out.items()}


TRAIN, EVAL, PROBE_SOURCE = STAT_SOURCES
LABELS = {TRAIN: "train", EVAL: "eval ", PROBE_SOURCE: "probe"}  # a row's source -> its line's tag


def _source(metrics: dict) -> str:
  """Which kind of report the metrics are."""
  if any(k.startswith(PROBE) for k in metrics):
    return PROBE_SOURCE
  return EVAL if any(k.startswith("eval/") for k in metrics) else TRAIN


class Reporter:
  """Called with (global step, metrics: episode means 'episode/...', Brax evaluation 'eval/...',
  'training/...' losses, 'curriculum/eps'); prints, logs to TensorBoard and the database."""

  def __init__(self, total_steps: int, start_step: int, db=None, run_id: str | None = None,
               tb_dir: str | None = None, stream=None, wall_offset: float = 0.0):
    self.total, self.start_step = total_steps, start_step
    self.db, self.run_id = db, run_id
    self.stream = stream  # None: sys.stdout as it is when a line is printed (not when this module loaded)
    self.session_t0 = time.time()
    self.t0 = self.session_t0 - wall_offset  # s: a resumed run's wall time continues from its checkpoint
    self.latest: dict[str, float] = {}
    self.latest_probe: dict[str, float] = {}
    self.writer = None
    if tb_dir:
      from tensorboardX import SummaryWriter  # noqa: PLC0415
      self.writer = SummaryWriter(tb_dir)

  def __call__(self, step: int, metrics: dict[str, Any]) -> dict[str, float]:
    now = time.time()
    sps = metrics.get("training/steps_per_s")  # the loop's: evaluation and checkpoint time excluded
    fig = summarize(metrics)
    eps = metrics.get("curriculum/eps")
    row = {"step": step, "wall_s": now - self.t0, "steps_per_s": sps, "eps": eps, **fig,
           "source": _source(metrics)}
    figures = {k: v for k, v in row.items() if v is not None and k != "source"}
    if fig and row["source"] == PROBE_SOURCE:  # the summary's figures: the last probe, and
      self.latest_probe = {f"probe_{k}": v for k, v in fig.items()}
    elif fig:  # the last report or evaluation
      self.latest = figures
    self._print(row)
    scalars = {k: float(np.asarray(v)) for k, v in metrics.items() if np.asarray(v).size == 1}
    if self.writer:
      for k, v in {**scalars, **{f"summary/{k}": v for k, v in figures.items()}}.items():
        self.writer.add_scalar(k, v, step)
      self.writer.flush()
    if self.db is not None and fig:
      self.db.log_stats(self.run_id, row, scalars)
    return row

  def _print(self, row: dict) -> None:
    f = lambda k, fmt: (fmt.format(row[k]) if row.get(k) is not None else "-")
    elapsed = time.time() - self.session_t0  # this process's share, for the ETA
    done = (row["step"] - self.start_step) / max(self.total - self.start_step, 1)
    eta = elapsed / done - elapsed if done > 0 else float("nan")
    print(f"[{LABELS[row['source']]}] {row['step']:>11,}/{self.total:,} ({100 * row['step'] / max(self.total, 1):5.1f}%) "
          f"{f('steps_per_s', '{:,.0f}')} steps/s | return {f('return_mean', '{:.3f}')} | "
          f"progress {f('progress_mean', '{:.3f}')} | eps {f('eps', '{:.2f}')} | "
          f"cog {f('cog_deviation_mean', '{:.3f}')} m | pitch rate {f('pitch_rate_mean', '{:.2f}')} rad/s | "
          f"tipped {f('tipped_rate', '{:.1%}')} | success {f('success_rate', '{:.1%}')} | "
          f"{row['wall_s']:,.0f} s, eta {eta:,.0f} s", file=self.stream or sys.stdout, flush=True)

  def close(self) -> None:
    if self.writer:
      self.writer.close()
      self.writer = None  # closing twice is harmless

"""Early-stop criteria of a run: `return[=X]`, the paper's (mean return of the training episodes
finished since the last report), or `success[=X]` (success of the probe on the task's probe scene,
train.core.probe: the trials of the final `train.evaluate --scene hardest`, or `--scene uniform` for
navigation), each optionally `xN`:
met by N reports in a row."""

from __future__ import annotations

import dataclasses

from scenes.kinds import scene_kind
from train.db import STAT_SOURCES

NO_EARLY_STOP = "none"  # --early-stop none: train every step whatever the preset says
EARLY_STOP_SUCCESS = 0.97  # success on the probe scene (the hardest staircase)
# reports in a row that must meet a criterion: two probes for success, since a policy that just
# reached 0.97 in one probe can score a few trials less in another compilation of the same trials
EARLY_STOP_TIMES = {"return": 1, "success": 2}
TRAIN, _, PROBE = STAT_SOURCES
CRITERIA = {"return": (TRAIN, "return_mean"), "success": (PROBE, "success_rate")}  # -> report source, column


@dataclasses.dataclass(frozen=True)
class EarlyStop:
  metric: str  # CRITERIA
  threshold: float
  times: int = 1  # reports of the criterion's source in a row that must meet it

  def __str__(self) -> str:
    return f"{self.metric}={self.threshold:g}" + (f"x{self.times}" if self.times != 1 else "")

  @property
  def needs_probe(self) -> bool:
    return CRITERIA[self.metric][0] == PROBE

  def met(self, row: dict) -> bool:
    """Whether a report row (train.core.progress.Reporter) reaches the threshold."""
    source, column = CRITERIA[self.metric]
    return row.get("source") == source and row.get(column) is not None and row[column] >= self.threshold

  def streak(self, streak: int, row: dict) -> int:
    """Reports in a row meeting the criterion, after this row (rows of other sources leave it)."""
    if row.get("source") != CRITERIA[self.metric][0]:
      return streak
    return streak + 1 if self.met(row) else 0


def _times(text: str, metric: str, value: str) -> tuple[str, int]:
  """(threshold text, times) of 'X', 'XxN' or ''."""
  value, sep, times = value.partition("x")
  if not sep:
    return value, EARLY_STOP_TIMES[metric]
  if not times.isdigit() or int(times) < 1:
    raise ValueError(f"--early-stop {text}: after 'x' comes a count of reports in a row (>= 1), got {times!r}")
  return value, int(times)


def criterion_name(early: EarlyStop | None) -> str:
  """How a run's early stop is named where one must be (a program's run tags): the criterion, or
  NO_EARLY_STOP for a run without one."""
  return str(early) if early else NO_EARLY_STOP


def parse_early_stop(text: str, cfg) -> EarlyStop:
  """'return', 'return=0.5', 'success', 'success=0.97', 'success=0.97x3' -> EarlyStop; ValueError
  naming the fault."""
  metric, _, value = text.partition("=")
  if metric not in CRITERIA:
    raise ValueError(f"--early-stop {text}: the criterion is one of {', '.join(CRITERIA)} "
                     "(optionally =THRESHOLD[xN])")
  value, times = _times(text, metric, value)
  if value:
    try:
      threshold = float(value)
    except ValueError:
      raise ValueError(f"--early-stop {text}: {value!r} is not a number") from None
  elif metric == "success":
    threshold = EARLY_STOP_SUCCESS
  else:
    threshold = scene_kind(cfg.scene.kind).early_stop_return(cfg.scene)
    if threshold is None:
      raise ValueError(f"--early-stop return: task {cfg.task} has no paper threshold; give return=X")
  if metric == "success" and not 0.0 <= threshold <= 1.0:
    raise ValueError(f"--early-stop {text}: a success threshold is in [0, 1]")
  if metric == "success" and cfg.scene.probe_scene is None:
    raise ValueError(f"--early-stop success: task {cfg.task} has no probe scene; use return=X")
  return EarlyStop(metric, threshold, times)

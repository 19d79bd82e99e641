"""Early-stop criteria of a run: `return[=X]`, the paper's (mean return of the training episodes
finished since the last report), or `success[=X]` (success of the hardest-staircase probe,
train.probe, which is the final `train.evaluate --scene hardest`)."""

from __future__ import annotations

import dataclasses

from train.db import STAT_SOURCES

EARLY_STOP_RETURN = {"up": 0.5, "down": 0.6}  # the paper's thresholds, by stair direction
EARLY_STOP_SUCCESS = 0.97  # success on the hardest staircase
TRAIN, _, HARDEST = STAT_SOURCES
CRITERIA = {"return": (TRAIN, "return_mean"), "success": (HARDEST, "success_rate")}  # -> report source, column


@dataclasses.dataclass(frozen=True)
class EarlyStop:
  metric: str  # CRITERIA
  threshold: float

  def __str__(self) -> str:
    return f"{self.metric}={self.threshold:g}"

  @property
  def needs_probe(self) -> bool:
    return CRITERIA[self.metric][0] == HARDEST

  def met(self, row: dict) -> bool:
    """Whether a report row (train.progress.Reporter) reaches the threshold."""
    source, column = CRITERIA[self.metric]
    return row.get("source") == source and row.get(column) is not None and row[column] >= self.threshold


def parse_early_stop(text: str, cfg) -> EarlyStop:
  """'return', 'return=0.5', 'success', 'success=0.97' -> EarlyStop; ValueError naming the fault."""
  metric, _, value = text.partition("=")
  if metric not in CRITERIA:
    raise ValueError(f"--early-stop {text}: the criterion is one of {', '.join(CRITERIA)} "
                     "(optionally =THRESHOLD)")
  if value:
    try:
      threshold = float(value)
    except ValueError:
      raise ValueError(f"--early-stop {text}: {value!r} is not a number") from None
  elif metric == "success":
    threshold = EARLY_STOP_SUCCESS
  else:
    threshold = EARLY_STOP_RETURN.get(cfg.scene.direction if cfg.scene.kind == "stairs" else "")
    if threshold is None:
      raise ValueError(f"--early-stop return: task {cfg.task} has no paper threshold; give return=X")
  if metric == "success" and not 0.0 <= threshold <= 1.0:
    raise ValueError(f"--early-stop {text}: a success threshold is in [0, 1]")
  if metric == "success" and cfg.scene.kind != "stairs":
    raise ValueError(f"--early-stop success: task {cfg.task} has no hardest staircase; use return=X")
  return EarlyStop(metric, threshold)

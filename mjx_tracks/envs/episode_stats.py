"""Per-episode figures from the sums of the per-step metrics over an episode: the one definition
used by evaluation (per trial), training reports (over Brax's episode metrics) and studies."""

from __future__ import annotations

import numpy as np


def episode_figures(sums: dict, length) -> dict[str, np.ndarray]:
  """sums: per-step metrics (mjx_tracks.envs.task_env.METRICS) summed over the episode; length in
  control steps. Success is reaching the goal (the step that reaches it ends the episode)."""
  f = lambda k: np.asarray(sums[k], np.float64)
  length = np.asarray(length, np.float64)
  on = f("on_stairs")
  return {
      "progress": f("progress"),
      "success": (f("goal_reached") > 0).astype(np.float64),
      "cog_deviation": np.where(on > 0, f("cog_deviation") / np.maximum(on, 1e-9), 0.0),  # m, on the stairs
      "pitch_rate": f("pitch_rate") / np.maximum(length, 1.0),  # rad/s, mean |pitch rate|
      "tipped_over": (f("tipped_over") > 0).astype(np.float64),
      "length": length,
  }

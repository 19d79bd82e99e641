"""Episode figures of the episodes that finished during an update, as sums the host adds up."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

COUNT = "episode/count"  # finished episodes in the sums
LATEST = "curriculum/"  # metrics reported at their latest value, not averaged over updates


def finished_sums(state_extras: dict) -> dict:
  """{episode/<metric>: sum over finished episodes, episode/count}: from Brax's EpisodeWrapper
  fields `episode_metrics` (per-episode sums) and `episode_done`, over any leading axes."""
  done = state_extras["episode_done"]
  out = {f"episode/{k}": jnp.sum(v * done) for k, v in state_extras["episode_metrics"].items()}
  out[COUNT] = jnp.sum(done)
  return out


def curriculum_figures(env_state) -> dict:
  """The curriculum's eps after the update (the same in every environment), if the env has one."""
  return {f"{LATEST}eps": env_state.info["eps"][0]} if "eps" in env_state.info else {}


class EpisodeAccumulator:
  """Adds up the per-update sums on the host; `take()` returns the means and starts over."""

  def __init__(self):
    self.sums: dict[str, float] = {}
    self.other: dict[str, list[float]] = {}

  def add(self, metrics: dict[str, np.ndarray]) -> None:
    for k, v in metrics.items():
      if k.startswith("episode/"):
        self.sums[k] = self.sums.get(k, 0.0) + float(v)
      elif k.startswith(LATEST):
        self.other[k] = [float(v)]
      else:
        self.other.setdefault(k, []).append(float(v))

  def take(self) -> dict[str, float]:
    """Means per finished episode (none if no episode finished) and of the training metrics."""
    n = self.sums.get(COUNT, 0.0)
    out = {k: v / n for k, v in self.sums.items() if k != COUNT} if n > 0 else {}
    out.update({k: float(np.mean(v)) for k, v in self.other.items()})
    if n > 0:
      out[COUNT] = n
    self.sums, self.other = {}, {}
    return out

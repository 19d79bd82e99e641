"""Curriculum state: eps from the returns (or progress) of the last N_e finished episodes.

A small pytree updated after each batched step, outside the per-environment vmap, from the batch's
done mask. Rules:
  "return"   (paper)          eps = clip(mean return of the last N_e finished episodes, 0, 1)
  "progress" (original code)  eps = clip(mean progress of the last N_e finished episodes, 0, 1)
Until N_e episodes have finished, the missing ones count as 0, so eps rises as the window fills
(one lucky first episode moves eps by 1 / N_e, not to 1). Episodes that did not finish are never
counted. Under pmap / shard_map, pass axis_name: the done
masks and values of every device are gathered first, so all devices hold the same state.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
from flax import struct

RULES = ("return", "progress")


@struct.dataclass
class CurriculumState:
  eps: jax.Array  # () difficulty in [0, 1]
  returns: jax.Array  # (N_e,) ring buffer of finished episodes' returns
  progress: jax.Array  # (N_e,) ring buffer of their progress
  head: jax.Array  # () int32, next ring slot
  finished: jax.Array  # () int32, episodes counted so far
  updates: jax.Array  # () int32, update calls so far


@dataclasses.dataclass(frozen=True)
class Curriculum:
  """Static settings: window N_e, rule, starting eps."""

  window: int  # N_e
  rule: str  # RULES
  eps0: float = 0.0  # eps before the first finished episode

  def __post_init__(self):
    if self.rule not in RULES:
      raise ValueError(f"unknown curriculum rule {self.rule!r}; known: {RULES}")
    if self.window < 1:
      raise ValueError("curriculum window N_e must be >= 1")
    if not 0.0 <= self.eps0 <= 1.0:
      raise ValueError("curriculum eps0 must be in [0, 1]")

  def init(self) -> CurriculumState:
    z = jnp.zeros(self.window, jnp.float32)
    i = jnp.zeros((), jnp.int32)
    return CurriculumState(jnp.float32(self.eps0), z, z, i, i, i)

  def update(self, s: CurriculumState, done: jax.Array, returns: jax.Array, progress: jax.Array,
             axis_name: str | None = None) -> CurriculumState:
    """Adds the finished episodes of one batched step (in batch order) and recomputes eps."""
    done = done.reshape(-1).astype(bool)
    returns, progress = returns.reshape(-1), progress.reshape(-1)
    if axis_name is not None:
      done, returns, progress = (jax.lax.all_gather(x, axis_name, tiled=True)
                                 for x in (done, returns, progress))
    n_done = done.sum().astype(jnp.int32)
    rank = jnp.cumsum(done) - 1  # order of each finished episode in this step
    # only the last `window` finished episodes of this step can survive: unique slots
    keep = done & (rank >= n_done - self.window)
    slot = jnp.where(keep, (s.head + rank) % self.window, self.window)  # out of range -> dropped
    ring_r = s.returns.at[slot].set(returns, mode="drop")
    ring_p = s.progress.at[slot].set(progress, mode="drop")
    finished = s.finished + n_done
    head = (s.head + n_done) % self.window
    valid = jnp.arange(self.window) < jnp.minimum(finished, self.window)
    values = ring_r if self.rule == "return" else ring_p
    mean = jnp.sum(jnp.where(valid, values, 0.0)) / self.window  # missing episodes count as 0
    eps = jnp.where(finished > 0, jnp.clip(mean, 0.0, 1.0), s.eps)
    return CurriculumState(eps.astype(jnp.float32), ring_r, ring_p, head, finished, s.updates + 1)

"""The training loop: one compiled update at a time, progress reports, timed checkpoints,
evaluations, early stop and stop requests (Ctrl-C / SIGTERM) between updates."""

from __future__ import annotations

import dataclasses
import time
from typing import Any, Callable

import jax
import numpy as np

from mjx_tracks.envs.wrappers import global_stats_to_json
from train.core.algos.episodes import EpisodeAccumulator
from train.core.checkpoints import RunCheckpoints
from train.core.early_stop import EarlyStop
from train.core.mesh import local_value, to_host


@dataclasses.dataclass
class Checkpointer:
  """Saves whole-state checkpoints of a run and records them in the database."""
  ckpts: RunCheckpoints
  meta: dict[str, Any]  # algorithm, task, run id, network spec
  learner: Any
  record: Callable[[int], None]  # called with the step of each checkpoint written
  every_s: float
  last_t: float = dataclasses.field(default_factory=time.monotonic)
  last_step: int | None = None

  def due(self) -> bool:
    return time.monotonic() - self.last_t >= self.every_s

  def save(self, state, step: int) -> None:
    """Checkpoints the state (unless this step is on disk already)."""
    self.last_t = time.monotonic()
    if step == self.last_step:
      return
    host = to_host(state)  # every process takes part in the gather; process 0 writes
    if jax.process_index() != 0:
      self.last_step = step
      return
    glob = jax.tree_util.tree_map(lambda x: x[0], host.env_state.info["global"])
    written = self.ckpts.save(step, host, self.learner.policy_params(host),
                              {**self.meta, "global": global_stats_to_json(glob)})
    self.last_step = step
    if written:
      self.record(step)


@dataclasses.dataclass
class LoopResult:
  state: Any
  step: int
  reason: str  # "done" | "early_stop" | "interrupted"


def _agree(stop: bool, checkpoint: bool) -> tuple[bool, bool]:
  """Every process takes the same decisions (any process stopping stops all; process 0's clock
  decides checkpoints)."""
  if jax.process_count() == 1:
    return stop, checkpoint
  from jax.experimental import multihost_utils  # noqa: PLC0415
  flags = multihost_utils.process_allgather(np.array([stop, checkpoint], np.int32))
  return bool(flags[:, 0].any()), bool(flags[0, 1])


@dataclasses.dataclass(frozen=True)
class Schedule:
  """What happens between updates, and when (in environment steps)."""
  report_every: int  # steps between progress reports
  early_stop: EarlyStop | None = None
  # (evaluate(state) -> metrics, every N steps): Brax's evaluator on uniform scenes, the hardest probe
  evaluations: tuple[tuple[Callable, int], ...] = ()
  milestones: tuple[int, ...] = ()  # budgets at which on_milestone(state, step, budget) runs
  on_milestone: Callable | None = None


class Loop:
  """Runs updates from a step until a total; see `run`."""

  def __init__(self, update, steps_per_update: int, checkpointer: Checkpointer, reporter, stop,
               schedule: Schedule):
    """update(state) -> (state, metrics); reporter(step, metrics) -> a report row; stop.requested:
    not None once a stop was asked for."""
    self.update, self.spu = update, steps_per_update
    self.milestones, self.on_milestone = schedule.milestones, schedule.on_milestone
    self.checkpointer, self.reporter, self.stop = checkpointer, reporter, stop
    self.report_every = max(schedule.report_every, steps_per_update)
    self.early = schedule.early_stop
    self.evals = [(f, every) for f, every in schedule.evaluations if f and every]

  def run(self, state, step: int, total: int) -> LoopResult:
    """Updates until `total` steps, an early stop or a stop request; the state at the end is
    checkpointed by the caller."""
    acc, pending = EpisodeAccumulator(), []
    next_report, next_evals = step + self.report_every, [self._next(step, e) for _, e in self.evals]
    self.checkpointer.last_t = self.mark_t = time.monotonic()
    self.mark_step, self.paused_s = step, 0.0
    reason, streak = "done", 0
    milestones = [b for b in self.milestones if b > step]  # a resumed run passed the others already
    while step < total and reason == "done":
      stop, ckpt = _agree(self.stop.requested is not None, self.checkpointer.due())
      if stop:
        reason = "interrupted"
        break
      if ckpt:
        self._paused(self.checkpointer.save, state, step)
      state, metrics = self.update(state)
      step += self.spu
      pending.append(metrics)
      while milestones and step >= milestones[0] and self.on_milestone is not None:
        self._paused(self.on_milestone, state, step, milestones.pop(0))
      rows = []
      if step >= next_report or step >= total:
        rows.append(self._report(step, acc, pending))
        pending, next_report = [], next_report + self.report_every
      for i, (evaluate, every) in enumerate(self.evals):
        if step >= next_evals[i]:
          rows.append(self.reporter(step, self._paused(evaluate, state)))
          next_evals[i] = self._next(step, every)
      if self.early is not None:
        for r in rows:
          streak = self.early.streak(streak, r)
        reason = "early_stop" if streak >= self.early.times else reason
    if pending:
      self._report(step, acc, pending)
    return LoopResult(state, step, reason)

  @staticmethod
  def _next(step: int, every: int) -> int:
    return (step // every + 1) * every

  def _paused(self, fn, *args):
    """fn(*args), its time left out of the training throughput; the updates already dispatched
    finish first, so their time stays in it."""
    jax.block_until_ready(args)
    t0 = time.monotonic()
    out = fn(*args)
    self.paused_s += time.monotonic() - t0
    return out

  def _report(self, step: int, acc: EpisodeAccumulator, pending: list) -> dict:
    for m in pending:
      acc.add({k: local_value(v) for k, v in m.items()})  # waits for the last update
    now = time.monotonic()
    sps = (step - self.mark_step) / max(now - self.mark_t - self.paused_s, 1e-9)
    self.mark_t, self.mark_step, self.paused_s = now, step, 0.0
    return self.reporter(step, {**acc.take(), "training/steps_per_s": sps})

"""The training loop: one compiled update at a time, progress reports, timed checkpoints,
evaluations, early stop and stop requests (Ctrl-C / SIGTERM) between updates."""

from __future__ import annotations

import dataclasses
import sys
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
  gap_s: float = 0.0  # s: the next timed checkpoint no sooner than this either (hold_off)
  unsettled: int | None = None  # the step whose save is in flight (recorded once it is on disk)

  def due(self) -> bool:
    self.poll()
    return time.monotonic() - self.last_t >= max(self.every_s, self.gap_s)

  def poll(self) -> None:
    """Records the save in flight if it is complete (without waiting for it)."""
    if self.unsettled is not None and not self.ckpts.writing():
      self.settle()

  def hold_off(self, gap_s: float) -> None:
    """The next timed checkpoint no sooner than gap_s after the last (nor than every_s)."""
    self.gap_s = gap_s

  def save(self, state, step: int, wait: bool = True) -> None:
    """Checkpoints the state (unless this step is saved already). wait=False (the timed rounds):
    the state is fetched to the host and orbax writes it in the background while training goes on;
    the next save, or settle(), waits for it. The database records a checkpoint once it is on
    disk (poll(), after each update, or the wait), so a recorded step can always be resumed from."""
    self.last_t = time.monotonic()
    if step != self.last_step:
      self.settle()
      host = to_host(state)  # every process takes part in the gather; process 0 writes
      if jax.process_index() == 0:
        glob = jax.tree_util.tree_map(lambda x: x[0], host.env_state.info["global"])
        if self.ckpts.save(step, host, self.learner.policy_params(host),
                           {**self.meta, "global": global_stats_to_json(glob)}, wait=False):
          self.unsettled = step
      self.last_step = step
    if wait:
      self.settle()

  def settle(self) -> None:
    """Waits for the save in flight, if any, then records its step."""
    if self.unsettled is None:
      return
    step, self.unsettled = self.unsettled, None
    self.ckpts.wait()
    self.record(step)


def settle_all(checkpointers) -> None:
  """Waits for every checkpoint still being written (after a failure: what was in flight stays
  resumable and recorded); one that fails is reported in a line, not raised over the failure
  being handled."""
  for c in checkpointers:
    try:
      c.settle()
    except Exception as e:  # noqa: BLE001  (orbax / tensorstore raise many types)
      print(f"warning: a checkpoint being written failed ({type(e).__name__}: {e})", file=sys.stderr)


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


class Clock:
  """Training time: wall time less the time spent evaluating, checkpointing or exporting between
  updates (shared by the runs of one program: one run's evaluation pauses them all)."""

  def __init__(self):
    self.paused_s = 0.0

  def paused(self, fn, *args):
    """fn(*args), its time left out of the training throughput; the updates already dispatched
    finish first, so their time stays in it."""
    jax.block_until_ready(args)
    t0 = time.monotonic()
    out = fn(*args)
    self.paused_s += time.monotonic() - t0
    return out


class Track:
  """One run's bookkeeping between updates: progress reports, evaluations, milestones and the
  early-stop streak; `index`: the run's slot in the metrics of a program of several runs (None: one run)."""

  def __init__(self, spu: int, reporter, schedule: "Schedule", clock: Clock, step: int, index: int | None = None):
    self.reporter, self.clock, self.index = reporter, clock, index
    self.report_every = max(schedule.report_every, spu)
    self.early, self.on_milestone = schedule.early_stop, schedule.on_milestone
    self.evals = [(f, every) for f, every in schedule.evaluations if f and every]
    self.milestones = [b for b in schedule.milestones if b > step]  # a resumed run passed the others already
    self.acc, self.pending, self.streak = EpisodeAccumulator(), [], 0
    self.next_report, self.next_evals = step + self.report_every, [_next(step, e) for _, e in self.evals]
    self.mark_t, self.mark_step, self.mark_paused = time.monotonic(), step, clock.paused_s

  def after_update(self, state_of: Callable[[], Any], step: int, metrics, total: int) -> str:
    """Everything due after the update that reached `step` ("early_stop" once the criterion is met,
    else "done"); state_of() gives the run's state (only asked for where something needs it)."""
    self.pending.append(metrics)
    while self.milestones and step >= self.milestones[0] and self.on_milestone is not None:
      self.clock.paused(self.on_milestone, state_of(), step, self.milestones.pop(0))
    rows = []
    if step >= self.next_report or step >= total:
      rows.append(self.report(step))
      self.next_report += self.report_every
    for i, (evaluate, every) in enumerate(self.evals):
      if step >= self.next_evals[i]:
        wanted = getattr(evaluate, "wanted", state_of)  # a program's share (AllRuns) reads all its runs' states
        rows.append(self.reporter(step, self.clock.paused(evaluate, wanted())))
        self.next_evals[i] = _next(step, every)
    if self.early is not None:
      for r in rows:
        self.streak = self.early.streak(self.streak, r)
      if self.streak >= self.early.times:
        return "early_stop"
    return "done"

  def report(self, step: int) -> dict:
    """The progress row of the updates since the last one (their metrics waited for)."""
    for m in self.pending:
      self.acc.add({k: local_value(v) if self.index is None else local_value(v)[self.index] for k, v in m.items()})
    self.pending = []
    now = time.monotonic()
    trained_s = now - self.mark_t - (self.clock.paused_s - self.mark_paused)
    sps = (step - self.mark_step) / max(trained_s, 1e-9)
    self.mark_t, self.mark_step, self.mark_paused = now, step, self.clock.paused_s
    return self.reporter(step, {**self.acc.take(), "training/steps_per_s": sps})

  def flush(self, step: int) -> None:
    """Reports the updates not reported yet."""
    if self.pending:
      self.report(step)


def _next(step: int, every: int) -> int:
  return (step // every + 1) * every


class Loop:
  """Runs updates from a step until a total; see `run`."""

  def __init__(self, update, steps_per_update: int, checkpointer: Checkpointer, reporter, stop,
               schedule: Schedule):
    """update(state) -> (state, metrics); reporter(step, metrics) -> a report row; stop.requested:
    not None once a stop was asked for."""
    self.update, self.spu, self.schedule = update, steps_per_update, schedule
    self.checkpointer, self.reporter, self.stop = checkpointer, reporter, stop

  def run(self, state, step: int, total: int) -> LoopResult:
    """Updates until `total` steps, an early stop or a stop request; the state at the end is
    checkpointed by the caller."""
    clock = Clock()
    track = Track(self.spu, self.reporter, self.schedule, clock, step)
    self.checkpointer.last_t = time.monotonic()
    reason = "done"
    while step < total and reason == "done":
      stop, ckpt = _agree(self.stop.requested is not None, self.checkpointer.due())
      if stop:
        reason = "interrupted"
        break
      if ckpt:
        clock.paused(self.checkpointer.save, state, step, False)
      state, metrics = self.update(state)
      step += self.spu
      reason = track.after_update(lambda: state, step, metrics, total)
    track.flush(step)
    return LoopResult(state, step, reason)

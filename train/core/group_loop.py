"""The training loop of several runs in one compiled program (`python -m train.run --seeds`): one
vmapped update at a time for every run, each run with its own reports, evaluations, milestones,
early stop and checkpoints (train.core.loop.Track). A run that stops early is finished there and
then (its `finish`: checkpoint and policy); its slot of the program goes on being computed, and
discarded, until every run has stopped (masking it would copy every run's state at every update)."""

from __future__ import annotations

import dataclasses
import time
from typing import Any, Callable

import jax

from train.core.loop import Checkpointer, Clock, LoopResult, Schedule, Track, _agree


@dataclasses.dataclass(frozen=True)
class Member:
  """One run of the program: where its records go, what happens between its updates, and how it
  is finished (finish(result) -> its summary: checkpoint and export)."""
  checkpointer: Checkpointer
  reporter: Any  # reporter(step, metrics) -> a report row
  schedule: Schedule
  finish: Callable[[LoopResult], Any] = lambda result: result


def run_slice(states, i: int):
  """Run i's state of the stacked states (the program's leading axis)."""
  return jax.tree_util.tree_map(lambda x: x[i], states)


class GroupLoop:
  """Runs the updates of several runs from a step until a total; see `run`."""

  def __init__(self, update, steps_per_update: int, members: list[Member], stop,
               after_update: Callable[[Any, int], None] = lambda states, step: None):
    """update(states) -> (states, metrics), both with a leading run axis; stop.requested: not None
    once a stop was asked for; after_update(states, step): told the states after each update,
    before any run's schedule (e.g. a probe of every run at once: train.core.probe.GroupProbe)."""
    self.update, self.spu, self.members, self.stop = update, steps_per_update, members, stop
    self.after_update = after_update

  def run(self, states, step: int, total: int) -> list[Any]:
    """Updates until `total` steps, every run's early stop or a stop request; each run is finished
    (Member.finish) as it ends; returns what each finish returned, in the members' order."""
    clock = Clock()
    tracks = [Track(self.spu, m.reporter, m.schedule, clock, step, index=i) for i, m in enumerate(self.members)]
    done: dict[int, Any] = {}

    def end(i: int, reason: str) -> None:
      tracks[i].flush(step)
      done[i] = self.members[i].finish(LoopResult(run_slice(states, i), step, reason))

    for m in self.members:
      m.checkpointer.last_t = time.monotonic()
    while step < total and len(done) < len(self.members):
      active = [i for i in range(len(self.members)) if i not in done]
      stop, ckpt = _agree(self.stop.requested is not None, self.members[active[0]].checkpointer.due())
      if stop:
        for i in active:
          end(i, "interrupted")
        break
      if ckpt:
        for i in active:
          clock.paused(self.members[i].checkpointer.save, run_slice(states, i), step)
      states, metrics = self.update(states)
      step += self.spu
      self.after_update(states, step)
      for i in active:
        if tracks[i].after_update(lambda i=i: run_slice(states, i), step, metrics, total) == "early_stop":
          end(i, "early_stop")
    for i in range(len(self.members)):
      if i not in done:
        end(i, "done")
    return [done[i] for i in range(len(self.members))]

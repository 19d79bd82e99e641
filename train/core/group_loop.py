"""The training loop of several runs in one compiled program (`python -m train.run --seeds`): one
vmapped update at a time for every run, each run with its own reports, evaluations, milestones,
early stop and checkpoints (train.core.loop.Track). A run that stops early is finished there and
then (its `finish`: checkpoint and policy); its slot of the program goes on being computed, and
discarded, until every run has stopped (masking it would copy every run's state at every update)."""

from __future__ import annotations

import dataclasses
import functools
import time
from typing import Any, Callable

import jax
import numpy as np

from train.core.ahead import CompiledAhead
from train.core.loop import Checkpointer, Clock, LoopResult, Schedule, Track, _agree
from train.core.mesh import to_host


@dataclasses.dataclass(frozen=True)
class Member:
  """One run of the program: where its records go, what happens between its updates, and how it
  is finished (finish(result) -> its summary: checkpoint and export)."""
  checkpointer: Checkpointer
  reporter: Any  # reporter(step, metrics) -> a report row
  schedule: Schedule
  finish: Callable[[LoopResult], Any] = lambda result: result


CHECKPOINT_SHARE = 0.1  # at most this share of a program's wall time goes to its timed checkpoint rounds


@jax.jit
def _device_slice(states, i):
  return jax.tree_util.tree_map(lambda x: x[i], states)


def run_slice(states, i: int):
  """Run i's state of the stacked states (the program's leading axis): of the program's states on
  the device, one program for the whole tree (not one dispatch per leaf); of a host tree (to_host's),
  numpy views. A host tree may hold a few device arrays: Brax's UInt64 (the observation
  normalizer's count) makes its parts jax arrays whenever it is built, to_host's result too; those
  are sliced where they are. (Until 2026-11-29 such a tree went to the device whole, every run's
  slice a copy of every run's state there and back: ~3.7 s of a 40-run round on an H200.)"""
  if any(isinstance(x, np.ndarray) for x in jax.tree_util.tree_leaves(states)):
    return jax.tree_util.tree_map(lambda x: x[i], states)
  return _device_slice(states, i)


class OnHost:
  """An update's metrics (arrays with a leading run axis), fetched to the host in one transfer by
  the first run's report that reads them and shared by every run's (each reads its own slot).
  Read run by run from the device, each report of each run fetched every metric of every update
  since the last (the paper preset, 40 runs: ~40 x 20 x 25 transfers per 1,000 steps)."""

  def __init__(self, metrics: dict):
    self._metrics = metrics

  @functools.cached_property
  def _host(self) -> dict:
    return to_host(self._metrics)

  def items(self):
    return self._host.items()


def round_gap(round_s: float, share: float = CHECKPOINT_SHARE) -> float:
  """Seconds to wait after a checkpoint round of round_s seconds so that rounds take at most
  `share` of the wall time (a round of 20 one-robot SAC runs with their replay buffers took 7 s on
  an H100, results/speed/profile/: 40 runs' at the default 60 s between rounds, a fifth of the
  program's time)."""
  return round_s * (1.0 / share - 1.0)


class AllRuns(CompiledAhead):
  """A computation over every run of a program at once (compute(states) -> one result per run, in
  the runs' order), asked for by each run in turn through its share (`member(i)`): the first run
  to ask after an update computes every run's (e.g. train.core.probe.GroupProbe,
  train.core.group_evaluator.GroupEvaluator). The program's loop names its states after each
  update (`at`)."""

  def __init__(self, compute: Callable[[Any], list]):
    self._compute, self._states, self._results = compute, None, None

  def at(self, states, step: int) -> None:
    """The program's states (a leading run axis) after the update that reached `step`: what the
    next question reads (nothing computed for them yet)."""
    del step  # every run's question at a step comes after the update that reached it
    self._states, self._results = states, None

  def member(self, i: int) -> "RunShare":
    return RunShare(self, i)

  def states(self):
    if self._states is None:
      raise RuntimeError(f"{type(self).__name__}: no states named yet (the program's loop calls at() after each update)")
    return self._states

  def result(self, i: int):
    """Run i's result for the states named last (computed for every run on the first question)."""
    if self._results is None:
      self.ready()  # its programs compiled ahead, if they were (train.core.ahead)
      self._results = self._compute(self.states())
    return self._results[i]


class RunShare:
  """Run i's share of an AllRuns computation, called as a run's evaluation is (train.core.loop.Track):
  with `wanted()`, the program's states, instead of run i's slice of them (no copy of a run's
  state is made for it)."""

  def __init__(self, all_runs: AllRuns, i: int):
    self.all_runs, self.i = all_runs, i

  def wanted(self):
    return self.all_runs.states()

  def __call__(self, states):
    del states  # the program's, named by at(): every run's result comes from them at once
    return self.all_runs.result(self.i)


class GroupLoop:
  """Runs the updates of several runs from a step until a total; see `run`."""

  def __init__(self, update, steps_per_update: int, members: list[Member], stop,
               after_update: Callable[[Any, int], None] = lambda states, step: None):
    """update(states) -> (states, metrics), both with a leading run axis; stop.requested: not None
    once a stop was asked for; after_update(states, step): told the states after each update,
    before any run's schedule (e.g. AllRuns.at: a probe or an evaluation of every run at once)."""
    self.update, self.spu, self.members, self.stop = update, steps_per_update, members, stop
    self.after_update = after_update

  def run(self, states, step: int, total: int) -> list[Any]:
    """Updates until `total` steps, every run's early stop or a stop request; each run is finished
    (Member.finish) as it ends; returns what each finish returned, in the members' order."""
    clock = Clock()
    tracks = [Track(self.spu, m.reporter, m.schedule, clock, step, index=i) for i, m in enumerate(self.members)]
    done: dict[int, Any] = {}

    def end(ending: list[int], reason: str) -> None:
      """Finishes the runs that end at this step: their checkpoints written at once, in the
      background, from one transfer of the states, then each run's finish (which waits for its own)."""
      for i in ending:
        tracks[i].flush(step)
      if len(ending) > 1:
        self._save_all(states, step, ending, wait=False)
      for i in ending:
        done[i] = self.members[i].finish(LoopResult(run_slice(states, i), step, reason))

    for m in self.members:
      m.checkpointer.last_t = time.monotonic()
    while step < total and len(done) < len(self.members):
      active = [i for i in range(len(self.members)) if i not in done]
      stop, ckpt = _agree(self.stop.requested is not None, self.members[active[0]].checkpointer.due())
      if stop:
        end(active, "interrupted")
        break
      if ckpt:
        self._checkpoint_round(states, step, active, clock)
      states, metrics = self.update(states)
      metrics = OnHost(metrics)
      for i in active:  # each run's last timed checkpoint recorded once it is on disk
        self.members[i].checkpointer.poll()
      step += self.spu
      self.after_update(states, step)
      end([i for i in active if tracks[i].after_update(lambda i=i: run_slice(states, i), step, metrics, total)
           == "early_stop"], "early_stop")
    end([i for i in range(len(self.members)) if i not in done], "done")
    return [done[i] for i in range(len(self.members))]

  def _save_all(self, states, step: int, runs: list[int], wait: bool) -> None:
    """Checkpoints of the given runs from one device-to-host transfer of the program's states."""
    host = to_host(states)
    for i in runs:
      self.members[i].checkpointer.save(run_slice(host, i), step, wait)

  def _checkpoint_round(self, states, step: int, active: list[int], clock: Clock) -> None:
    """Every active run's timed checkpoint, written in the background while training goes on (the
    round waits for the last round's writes, the transfer and the start of each write); the next
    round waits round_gap(this round's seconds), or --checkpoint-every if longer."""
    t0 = time.monotonic()
    clock.paused(self._save_all, states, step, active, False)
    gap = round_gap(time.monotonic() - t0)
    for i in active:
      self.members[i].checkpointer.hold_off(gap)

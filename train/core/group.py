"""Several runs in one compiled program (`python -m train.run --seeds 0,1,2`, with `--tasks A,B` of
several tasks): runs that differ only in their seed, or also in their task where the program takes
the tasks' differences as data (mjx_tracks.envs.task_data), train as one vmapped update on one device. Each run keeps everything a run of
its own has: its folder (run.json, checkpoints/, policy/, tb/), its database rows, its probe and
early stop (a finished run is checkpointed and exported at once, its slot computed and
discarded from then on), its milestones; `python -m train.run --resume
RUN` continues any of them alone. Brax's evaluation of every run is one unroll
(train.core.group_evaluator.GroupEvaluator; per run where a batch statistic would couple the runs),
the probe of every run one rollout (train.core.probe.GroupProbe)."""

from __future__ import annotations

import dataclasses
import os
import sys
import time
from typing import Any, Callable

import jax
import jax.numpy as jnp

from mjx_tracks.envs.task_data import TaskData, packed_keys, packing_conflict, stacked, task_data
from train.core import ahead
from train.core.build import Training, build, has_evaluations, learner_on
from train.core.early_stop import criterion_name
from train.core.group_evaluator import GroupEvaluator, evaluations_shared
from train.core.group_loop import GroupLoop, Member
from train.core.loop import settle_all
from train.core.plan import RunError, RunPlan
from train.core.probe import GroupProbe
from train.core.progress import Reporter
from train.core.run_record import several_stops, several_tasks
from train.core.session import SessionOptions, checkpointer_of, evaluator_of, finish_run, schedule_of


class Prefixed:
  """A text stream that starts each line with a run's tag (run_tags), for one shared terminal."""

  def __init__(self, tag: str, stream=None):
    self.tag, self.stream, self.fresh = tag, stream, True

  def write(self, text: str) -> int:
    out = self.stream or sys.stdout
    for piece in text.splitlines(keepends=True):
      out.write((self.tag if self.fresh else "") + piece)
      self.fresh = piece.endswith("\n")
    return len(text)

  def flush(self) -> None:
    (self.stream or sys.stdout).flush()


def build_group(plans: list[RunPlan]) -> Training:
  """The one build the runs share (the first plan's; the others differ in seed and folder, and
  in task and early stop where their configs differ only in what the program takes as data:
  mjx_tracks.envs.task_data)."""
  base = plans[0]
  for p in plans[1:]:
    conflict = packing_conflict(base.cfg, p.cfg)
    if conflict is not None:
      raise RunError(f"--tasks: {base.task} and {p.task} differ in {conflict}; the runs of one program may "
                     f"differ in {', '.join(packed_keys(base.cfg))} only")
    if dataclasses.replace(p, seed=base.seed, out_dir=base.out_dir, run_id=base.run_id, task=base.task,
                           cfg=base.cfg, early_stop=base.early_stop, overrides=base.overrides) != base:
      raise RunError("--seeds: the runs of one program may differ in their seed, task and early stop only "
                     "(an early stop on success probes every run: with a preset that probes none, keep it apart)")
  t = build(base)
  if t.mesh.devices.size != 1:
    raise RunError(f"--seeds trains on one device; this process sees {t.mesh.devices.size} "
                   "(limit it, e.g. CUDA_VISIBLE_DEVICES=0)")
  return t


def state_bytes(t: Training) -> int:
  """Bytes of one run's learner state (parameters, optimizer, environments, replay buffer)."""
  return sum(a.size * a.dtype.itemsize for a in jax.tree_util.tree_leaves(t.abstract))


def free_bytes() -> int | None:
  """Memory free on the device the program runs on (bytes), where it can be told."""
  device = jax.devices()[0]
  stats = device.memory_stats() if device.platform != "cpu" else None
  if stats and "bytes_limit" in stats:
    return stats["bytes_limit"] - stats.get("bytes_in_use", 0)
  try:
    return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
  except (ValueError, OSError, AttributeError):
    return None


def check_memory(t: Training, n: int, free: int | None) -> None:
  """Refuses (RunError, one line) n runs whose states and the update's copy of them do not fit."""
  need = 2 * n * state_bytes(t)  # the states and the update's output (donation frees the input only after)
  if free is not None and need > free:
    hint = " or a smaller replay buffer (--hp max_replay_size=N)" if t.plan.algo == "sac" else ""
    raise RunError(f"--seeds: {n} runs need ~{need / 1e9:.1f} GB for their states, more than the "
                   f"{free / 1e9:.1f} GB free on {jax.devices()[0].platform}; fewer seeds{hint}")


def group_tasks(t: Training, plans: list[RunPlan]) -> TaskData | None:
  """Each run's task as data, stacked (mjx_tracks.envs.task_data); None where every run has t's."""
  if all(p.cfg == t.plan.cfg for p in plans):
    return None
  return stacked([task_data(p.cfg, t.plan.cfg) for p in plans])


def init_group(t: Training, plans: list[RunPlan], tasks: TaskData | None):
  """Each run's fresh learner state (its seed's, its task's scenes), stacked."""
  keys = jnp.stack([jax.random.PRNGKey(p.seed) for p in plans])
  if tasks is None:
    return jax.jit(jax.vmap(t.learner.init))(keys)
  return jax.jit(jax.vmap(lambda k, d: learner_on(t, d).init(k)))(keys, tasks)


def lower_group(t: Training, n: int, tasks: TaskData | None = None):
  """The vmapped update of n runs (tasks: their tasks as data, group_tasks), lowered with the
  states donated: update(states) or, with tasks, update(states, tasks)."""
  shaped = jax.tree_util.tree_map(lambda a: jax.ShapeDtypeStruct((n,) + a.shape, a.dtype), t.abstract)
  if tasks is None:
    return jax.jit(jax.vmap(t.learner.update), donate_argnums=0).lower(shaped)
  return jax.jit(jax.vmap(lambda s, d: learner_on(t, d).update(s)), donate_argnums=0).lower(shaped, tasks)


def compile_group(t: Training, n: int, stream=None, tasks: TaskData | None = None,
                  meanwhile: Callable[[], None] = lambda: None):
  """(update(states) of n runs (lower_group's) compiled ahead of time, the seconds that took);
  meanwhile(): called once the update is lowered, while XLA compiles it (train.core.ahead.start)."""
  stream = stream or sys.stdout  # as it is now (a test's capture), not as it was at import
  print(f"compiling the training step of {n} runs in one program ...", file=stream, flush=True)
  t0 = time.time()
  lowered = lower_group(t, n, tasks)
  meanwhile()
  compiled = lowered.compile()
  seconds = time.time() - t0
  print(f"compiled in {seconds:,.0f} s", file=stream, flush=True)
  return (compiled if tasks is None else (lambda states: compiled(states, tasks))), seconds


def run_tags(plans: list[RunPlan]) -> list[str]:
  """How a program's output names each of its runs: s<seed>, with <task> in front in a program of
  several tasks, and the run's early stop (e.g. return=0.5, none) in front of that in a program of
  several early stops."""
  stops = [criterion_name(p.early_stop) for p in plans]
  tasks, criteria = several_tasks(plans), several_stops(stops)
  return [" ".join([*([stop] if criteria else []), *([p.task] if tasks else []), f"s{p.seed}"])
          for p, stop in zip(plans, stops)]


def _member(t: Training, plan: RunPlan, db, shared: tuple, options: SessionOptions,
            on_end: Callable[[dict], None], tag: str) -> tuple[Member, Reporter]:
  """Run `plan`'s records, schedule and finish in the program; shared: (evaluate, probe) of this run;
  on_end(summary): told as soon as the run has ended, checkpointed and exported; tag: its name in
  the program's output (run_tags)."""
  ti = dataclasses.replace(t, plan=plan)
  checkpointer = checkpointer_of(ti, db, options)
  reporter = Reporter(plan.total_steps, 0, db, plan.run_id, f"{plan.out_dir}/tb", stream=Prefixed(tag + " "))

  def finish(result) -> dict[str, Any]:  # the run's checkpoint, policy and summary, as soon as it ends
    try:
      summary = finish_run(ti, result, checkpointer, reporter)
    finally:
      reporter.close()
    on_end(summary)
    return summary

  return Member(checkpointer, reporter, schedule_of(ti, *shared), finish), reporter


def prepare_group(plans: list[RunPlan]) -> Training:
  """The shared build, checked to fit on the device (RunError before any record is written)."""
  t = build_group(plans)
  check_memory(t, len(plans), free_bytes())
  return t


def group_evaluations(t: Training, plans: list[RunPlan], configs: list | None = None) -> tuple[GroupEvaluator | None, list]:
  """(the shared evaluation or None, each run's evaluate(state) or None): every run's Brax evaluation
  in one unroll where their episodes share no statistic (evaluations_shared), else each run's own
  evaluator in turn; configs: each run's task config where the runs' tasks differ."""
  if not has_evaluations(t):
    return None, [None] * len(plans)
  if not evaluations_shared(t.plan.cfg):  # each run's own evaluator, on its own task's scenes
    return None, [evaluator_of(dataclasses.replace(t, plan=dataclasses.replace(t.plan, cfg=p.cfg, seed=p.seed)))
                  for p in plans]
  shared = GroupEvaluator(t, [p.seed for p in plans], configs)
  return shared, [shared.member(i) for i in range(len(plans))]


def train_group(t: Training, plans: list[RunPlan], dbs: list, stop, options: SessionOptions = SessionOptions(),
                on_end: Callable[[int, dict], None] = lambda i, summary: None) -> list[dict[str, Any]]:
  """Trains the runs (t: prepare_group's) as one program until their total steps, early stops or a
  stop request, each run's records in its database (dbs[i]: runs of several tasks have one each
  beside OUT/<task>); each run is checkpointed and exported as it ends, then on_end(its index, its
  summary) records it (a run that ended stays ended if the program fails later); returns each
  run's summary (as train.core.session.train)."""
  tasks = group_tasks(t, plans)
  configs = None if tasks is None else [p.cfg for p in plans]  # each run's, where the runs' tasks differ
  states = init_group(t, plans, tasks)
  evaluate, evaluations = group_evaluations(t, plans, configs)
  probe = GroupProbe(t, configs=configs) if any(p.probe_every for p in plans) else None  # every run's trials in one rollout
  shared, parts = [s for s in (evaluate, probe) if s is not None], []

  def after_update(states, step: int) -> None:
    for s in shared:
      s.at(states, step)
  if options.split_update == "on":
    print("note: --split-update on applies to a run of one task; a program of several runs keeps its update whole",
          flush=True)
  try:  # the evaluations trace once the update is lowered, and compile with it and while the runs train
    update, seconds = compile_group(t, len(plans), tasks=tasks,
                                    meanwhile=lambda: ahead.start(options.compile_ahead, shared, states))
    for db, plan in zip(dbs, plans):
      db.compiled(plan.run_id, 0, seconds)
    parts = [_member(t, p, dbs[i], (evaluations[i], probe and probe.member(i)), options,
                     lambda summary, i=i: on_end(i, summary), tag)
             for i, (p, tag) in enumerate(zip(plans, run_tags(plans)))]
    return GroupLoop(update, t.learner.steps_per_update, [m for m, _ in parts], stop,
                     after_update).run(states, 0, plans[0].total_steps)
  finally:
    settle_all(m.checkpointer for m, _ in parts)
    ahead.settle(shared)
    for _, reporter in parts:
      reporter.close()

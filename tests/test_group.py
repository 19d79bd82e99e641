"""Several runs in one compiled program (`train.run --seeds`): the per-run loop with fakes, the
program's runs kept apart, the command end to end, and its benchmark (`train.bench group`)."""

import json
import os
import time
import types

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import TRAIN_TINY

from train import db as dbmod
from train import evaluate, run
from train.bench.__main__ import main as bench_main
from train.core.checkpoints import RunCheckpoints
from train.core.early_stop import EarlyStop
from train.core.group_loop import GroupLoop, Member
from train.core.loop import Checkpointer, Schedule


class Rows:
  def __init__(self):
    self.rows = []

  def __call__(self, step, metrics):
    row = {"step": step, "source": "probe" if "probe/success_rate" in metrics else "train",
           "success_rate": metrics.get("probe/success_rate")}
    self.rows.append(row)
    return row


class NoSaves(Checkpointer):
  """The loop's checkpoints, not written (these programs' states are not training states)."""

  def save(self, state, step, wait=True):
    self.last_t = time.monotonic()


def test_each_run_stops_on_its_own_probe_and_is_finished_with_the_state_it_had_then():
  """Two runs of 100-step updates; run 0's probe reads 0.98 from its second probe, run 1's never:
  run 0 is finished at step 400 with the state it had then (its slot computed on, and discarded),
  run 1 trains to the end."""
  probe_values = {0: iter([0.5, 0.98, 0.99]), 1: iter([0.1] * 20)}
  finished = []

  def update(states):  # every slot counts the updates it has seen
    return states + 1, {"episode/sum_reward": np.zeros(2)}

  members, reporters = [], []
  for i in (0, 1):
    reporters.append(Rows())
    probe = lambda s, i=i: {"probe/success_rate": next(probe_values[i])}  # noqa: E731
    members.append(Member(NoSaves(None, {}, None, lambda step: None, every_s=1e9), reporters[i],
                          Schedule(100, EarlyStop("success", 0.97, 1), ((probe, 200),)),
                          lambda r, i=i: finished.append(i) or (r.reason, r.step, int(r.state))))
  results = GroupLoop(update, 100, members, types.SimpleNamespace(requested=None)).run(np.zeros(2, np.int64), 0, 1_000)
  assert results == [("early_stop", 400, 4), ("done", 1_000, 10)] and finished == [0, 1]
  assert [r["step"] for r in reporters[0].rows if r["source"] == "probe"] == [200, 400]
  assert len([r for r in reporters[1].rows if r["source"] == "probe"]) == 5


def test_a_programs_checkpoint_rounds_take_at_most_a_tenth_of_its_wall_time():
  """A round is one transfer of the program's states to the host, then each run's checkpoint of
  its own slice of them; a round of d seconds holds the next off for 9 d (round_gap) where that is
  longer than --checkpoint-every (here 0: every update, were it not for the round's length)."""
  saved = []

  class SlowSaves(Checkpointer):
    def save(self, state, step, wait=True):
      time.sleep(0.05)
      saved.append((type(state), int(state), step, wait))
      self.last_t = time.monotonic()

  members = [Member(SlowSaves(None, {}, None, lambda step: None, every_s=0.0), Rows(), Schedule(100), lambda r: r.step)
             for _ in (0, 1)]
  results = GroupLoop(lambda s: (s + 1, {}), 100, members, types.SimpleNamespace(requested=None)).run(
      jnp.zeros(2, jnp.int32), 0, 300)
  assert results == [300, 300]
  # one round, at the start, written in the background; then the runs' final checkpoints, together
  assert [(value, step, wait) for _, value, step, wait in saved] == [(0, 0, False)] * 2 + [(3, 300, False)] * 2
  assert all(issubclass(kind, np.generic) for kind, *_ in saved)  # host slices, not device ones
  assert all(0.9 <= m.checkpointer.gap_s < 10 for m in members)  # 9 x a round of ~0.1 s


def test_an_updates_metrics_go_to_the_host_once_for_every_runs_report_and_each_run_reads_its_own(monkeypatch):
  from train.core import group_loop
  fetched = []
  monkeypatch.setattr(group_loop, "to_host", lambda tree: fetched.append(isinstance(tree, dict)) or jax.device_get(tree))

  class Kept(Rows):
    def __call__(self, step, metrics):
      self.rows.append(metrics)
      return {"step": step}

  def update(states):  # run i finishes 1 episode of return i + 1 and 2 of return 0 per update
    return states, {"episode/sum_reward": jnp.arange(1.0, 4.0), "episode/count": jnp.full(3, 3.0),
                    "training/loss": jnp.asarray([0.5, 1.5, 2.5])}

  reporters = [Kept() for _ in range(3)]
  members = [Member(NoSaves(None, {}, None, lambda step: None, every_s=1e9), r, Schedule(200), lambda r: r.step)
             for r in reporters]
  GroupLoop(update, 100, members, types.SimpleNamespace(requested=None)).run(jnp.zeros(3), 0, 400)
  assert fetched.count(True) == 4  # one transfer of metrics per update, not one per run and metric
  for i, r in enumerate(reporters):
    assert [m["episode/sum_reward"] for m in r.rows] == pytest.approx([(i + 1) / 3] * 2)  # per episode, its own
    assert [m["training/loss"] for m in r.rows] == pytest.approx([0.5 + i] * 2)


def test_a_stop_request_ends_every_run_of_the_program():
  members = [Member(NoSaves(None, {}, None, lambda step: None, every_s=1e9), Rows(), Schedule(100),
                    lambda r: (r.reason, r.step)) for _ in (0, 1)]
  results = GroupLoop(lambda s: (s + 1, {}), 100, members, types.SimpleNamespace(requested=15)).run(np.zeros(2), 0, 500)
  assert results == [("interrupted", 0)] * 2


def _spied(monkeypatch, names: dict, ahead_event: str) -> list:
  """The order in which train.core.group's functions `names` (-> the event each names) return and
  train.core.ahead.start is called with a computation to compile (-> ahead_event)."""
  from train.core import ahead, group
  order = []
  for name, event in names.items():
    real = getattr(group, name)
    monkeypatch.setattr(group, name, lambda *a, real=real, event=event, **k: (real(*a, **k), order.append(event))[0])
  start = ahead.start
  monkeypatch.setattr(ahead, "start", lambda choice, computations, example: (
      order.append(ahead_event) if any(c is not None for c in computations) else None,
      start(choice, computations, example))[1])
  return order


def test_seeds_train_as_runs_of_their_own_in_one_program(tmp_path, capsys, monkeypatch):
  out, database = str(tmp_path / "group"), str(tmp_path / "db.sqlite")
  order = _spied(monkeypatch, {"lower_group": "lowered", "compile_group": "compiled", "_member": "run's records made"},
                 "ahead started")
  assert run.main([*TRAIN_TINY, "--seeds", "0,1", "--steps", "512", "--out", out, "--db", database,
                   "--probe-every", "512", "--checkpoint-every", "0", "--compile-ahead", "on"]) == 0
  # the probe traces once the training step is lowered (not beside its tracing), then compiles while
  # XLA compiles the step (train.core.ahead)
  assert order == ["lowered", "ahead started", "compiled", "run's records made", "run's records made"]
  said = capsys.readouterr().out
  assert "2 runs" in said and "in one program" in said and "s0 [train]" in said and "s1 [probe]" in said
  d = dbmod.ExperimentDB(database)
  runs = {r["seed"]: r for r in d.runs()}
  assert set(runs) == {0, 1} and all(r["status"] == "done" for r in runs.values())
  compiled = [[e["detail"] for e in d.events(r["run_id"]) if e["event"] == "compiled"] for r in runs.values()]
  assert compiled[0] == compiled[1] and len(compiled[0]) == 1  # one program: one compilation, each run's record
  params, probes = [], []
  for seed in (0, 1):
    folder = os.path.join(out, f"s{seed}")
    record = json.load(open(os.path.join(folder, "run.json")))
    assert record["seed"] == seed and record["run_id"] == runs[seed]["run_id"]
    assert RunCheckpoints(folder).latest_step() == 512 and os.path.isdir(os.path.join(folder, "policy"))
    sources = {(r["source"], r["step"]) for r in d.stats(record["run_id"])}
    assert ("train", 512) in sources and ("probe", 512) in sources  # one update, then its probe
    params.append(RunCheckpoints(folder).restore()[0])
    (probe,) = [r for r in d.stats(record["run_id"]) if (r["source"], r["step"]) == ("probe", 512)]
    probes.append(probe)
  assert probes[0]["progress_mean"] != probes[1]["progress_mean"]
  # the program's probe (every run's trials in one rollout) reads what `train.evaluate` of the run's
  # policy reads on the same trials: the second run's own, not its neighbour's (their probes differ)
  report = str(tmp_path / "eval-s1.json")
  assert evaluate.main([os.path.join(out, "s1"), "--scene", "hardest", "--out", report, "--db", database]) == 0
  alone = json.load(open(report))["metrics"]
  # the same trials in another program (vmapped): a trial's physics may round differently
  assert probes[1]["success_rate"] == pytest.approx(alone["success"]["mean"], abs=0.011)  # one trial of 100
  assert probes[1]["progress_mean"] == pytest.approx(alone["progress"]["mean"], abs=1e-3)
  assert probes[0]["progress_mean"] != pytest.approx(alone["progress"]["mean"], abs=1e-3)  # not the neighbour's
  leaves = [jax.tree_util.tree_leaves(p) for p in params]
  assert any(np.asarray(a).shape == np.asarray(b).shape and not np.array_equal(a, b)
             for a, b in zip(*leaves))  # two seeds, two runs
  # any run of the program continues alone, as a run of its own
  assert run.main(["--resume", os.path.join(out, "s1"), "--steps", "1024", "--db", database]) == 0
  assert "from its checkpoint at step 512" in capsys.readouterr().out
  assert RunCheckpoints(os.path.join(out, "s1")).latest_step() == 1024


def test_the_group_bench_times_single_runs_and_one_program_of_all(tmp_path, monkeypatch):
  """N runs as one program against single runs, each process timed (with the study tests' stand-in
  for train.run: no JAX); every run of both kinds trains its whole budget, the figures follow
  from the rows, and train.run itself takes the arguments the bench gives it."""
  from train.bench import group as bench_group
  fake = os.path.join(os.path.dirname(__file__), "fake_study_run.py")
  monkeypatch.setattr(bench_group, "TRAIN", (fake, "train"))
  out, work = str(tmp_path / "group.json"), tmp_path / "work"
  work.mkdir()
  given = ["--task", "asc-inc-cog", "--algo", "ppo", "--preset", "cpu"]
  assert bench_main(["group", "--runs", "3", "--singles", "2", "--steps", "300", "--work", str(work),
                     "--out", out, "--", *given]) == 0
  result = json.load(open(out))
  assert [r["mode"] for r in result["rows"]] == ["single", "single", "group"]
  single = sum(r["process_wall_s"] for r in result["rows"][:2]) / 2
  group = result["rows"][-1]["process_wall_s"]
  assert result["group_in_singles"] == round(group / single, 2) and result["group_speedup"] == round(3 * single / group, 2)
  for name, seeds in (("single-s0", {0}), ("single-s1", {1}), ("group", {0, 1, 2})):  # whole budgets
    runs = dbmod.ExperimentDB(str(work / f"{name}.sqlite")).runs()
    assert {r["seed"] for r in runs} == seeds and all(r["status"] == "done" for r in runs)
    assert all(os.path.isdir(os.path.join(r["out_dir"], "checkpoints", "300")) for r in runs)
  assert result["train_args"] == [*given, "--steps", "300", "--early-stop", "none"]
  for extra in (["--seed", "0"], ["--seeds", "0,1,2"]):  # train.run's own parser takes what the bench gives
    parsed = run.parser().parse_args([*result["train_args"], *extra, "--out", "o", "--db", "d"])
    assert parsed.early_stop == "none" and parsed.steps == 300


def test_the_group_bench_with_tasks_times_the_runs_spread_over_them_against_the_seeds_program(tmp_path, monkeypatch):
  """--tasks: the seeds program of the first task, then the same number of runs over the tasks in
  one program (train.run --tasks), every run its whole budget; tasks_in_seeds from the rows."""
  from train.bench import group as bench_group
  monkeypatch.setattr(bench_group, "TRAIN", (os.path.join(os.path.dirname(__file__), "fake_study_run.py"), "train"))
  out, work = str(tmp_path / "group.json"), tmp_path / "work"  # --work made where it is missing
  assert bench_main(["group", "--runs", "4", "--singles", "0", "--tasks", "asc-inc-cog,des-inc-ang", "--steps", "200",
                     "--work", str(work), "--out", out, "--", "--task", "nav", "--algo", "ppo", "--preset", "cpu"]) == 0
  result = json.load(open(out))
  assert [r["mode"] for r in result["rows"]] == ["group", "tasks"] and "group_in_singles" not in result
  assert result["tasks_in_seeds"] == round(result["rows"][1]["process_wall_s"] / result["rows"][0]["process_wall_s"], 2)
  for name, runs_wanted in (("group", {("asc-inc-cog", s) for s in range(4)}),
                            ("tasks", {(t, s) for t in ("asc-inc-cog", "des-inc-ang") for s in (0, 1)})):
    runs = dbmod.ExperimentDB(str(work / f"{name}.sqlite")).runs()
    assert {(r["task"], r["seed"]) for r in runs} == runs_wanted and all(r["status"] == "done" for r in runs)
  assert bench_main(["group", "--runs", "3", "--tasks", "asc-inc-cog,des-inc-ang"]) == 2  # 2 tasks do not divide 3


def test_the_group_bench_refuses_a_group_of_one_in_one_line(capsys):
  assert bench_main(["group", "--runs", "1"]) == 2
  assert capsys.readouterr().err.startswith("error: --runs >= 2")


@pytest.mark.parametrize("argv, words", [
    (["--seeds", "0,1", "--seed", "3"], "does not go with --seed"),
    (["--seeds", "0,x"], "whole numbers"),
    (["--seeds", "2,2"], "two different seeds"),
    (["--seeds", "4"], "two different seeds"),
    (["--seeds", "0,1", "--library", "brax"], "does not go with --library brax")])
def test_bad_seeds_fail_with_one_line_before_anything_is_written(argv, words, tmp_path, capsys):
  assert run.main([*TRAIN_TINY, *argv, "--out", str(tmp_path / "g")]) == 2
  assert words in capsys.readouterr().err and not os.path.exists(tmp_path / "g")


def test_the_runs_of_one_program_do_not_see_each_other(tmp_path):
  """Each run starts from its separate run's state; run 0's update, with run 1 being seed 1 or seed
  2: bit for bit the same (no statistic, curriculum or normalizer shared across the program's
  runs); run 1's differs."""
  from train.core.group import build_group, compile_group
  from train.core.plan import plan_run
  t = build_group([plan_run(run.parser().parse_args([*TRAIN_TINY, "--seed", "0", "--out", str(tmp_path / "r")]))])
  update, _ = compile_group(t, 2)
  init = jax.jit(jax.vmap(t.learner.init))
  alone = jax.jit(t.learner.init)(jax.random.PRNGKey(2))  # each run starts from its separate run's state
  together = init(jnp.stack([jax.random.PRNGKey(0), jax.random.PRNGKey(2)]))
  assert all(np.array_equal(np.asarray(a), np.asarray(b)[1])
             for a, b in zip(jax.tree_util.tree_leaves(alone), jax.tree_util.tree_leaves(together)))
  out = [update(init(jnp.stack([jax.random.PRNGKey(0), jax.random.PRNGKey(other)])))[0] for other in (1, 2)]
  leaves = [jax.tree_util.tree_leaves(o) for o in out]
  assert all(np.array_equal(np.asarray(a)[0], np.asarray(b)[0]) for a, b in zip(*leaves))
  assert not all(np.array_equal(np.asarray(a)[1], np.asarray(b)[1]) for a, b in zip(*leaves))


def test_runs_whose_states_do_not_fit_are_refused_in_one_line(tmp_path):
  from train.core.group import build_group, check_memory, state_bytes
  from train.core.plan import RunError, plan_run
  t = build_group([plan_run(run.parser().parse_args(["--task", "asc-inc-cog", "--algo", "sac", "--preset", "paper",
                                                      "--out", str(tmp_path / "r")]))])
  one = state_bytes(t)
  assert one > 4e8  # the paper preset's 1,000,000-transition replay buffer dominates
  check_memory(t, 20, 41 * one)
  with pytest.raises(RunError, match=r"20 runs need ~.* GB .* fewer seeds or a smaller replay buffer"):
    check_memory(t, 20, 39 * one)


def test_a_question_for_every_run_is_computed_once_per_update_and_each_run_reads_its_own():
  from train.core.group_loop import AllRuns
  calls = []
  shared = AllRuns(lambda states: calls.append(states) or [f"run {i} of {states}" for i in range(2)])
  first, second = shared.member(0), shared.member(1)
  with pytest.raises(RuntimeError, match="no states named yet"):
    first(None)
  shared.at("A", 10)
  assert first.wanted() == "A" and (second(None), first(None)) == ("run 1 of A", "run 0 of A")
  shared.at("B", 20)
  assert first(None) == "run 0 of B" and calls == ["A", "B"]

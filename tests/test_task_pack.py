"""Runs of several tasks in one program (`train.run --tasks A,B --seeds ...`; mjx_tracks.envs.task_data)
and of several early stops (`--early-stops`):
each run's view of the program's environment starts, steps and rewards as its own task's
environment does; each run starts from the state it would start from alone; the program's probe
and evaluations of each run are those of its own task (here through `train.evaluate`, which runs
the probe's trials; Brax's evaluation of a program of several tasks: tests/test_evaluator.py);
configs that differ beyond the data a program takes are refused in one line before anything is
written."""

import dataclasses
import json
import os

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from helpers import PACK, TINY, TINY_SETTINGS, await_runs_on_stdin, pack_plans
from mjx_tracks.envs.config import load_config
from mjx_tracks.envs.task_data import packing_conflict, task_data
from mjx_tracks.envs.task_env import TrackedRobotEnv
from train import run
from train.core.build import build
from train.core.group import build_group, group_tasks, init_group
from train.core.group_loop import run_slice

(ASC, _), (DES, _) = PACK  # direction, sampler and reward kind all differ
SAC_TINY = ["--algo", "sac", "--preset", "cpu", *TINY]


@pytest.fixture(scope="module")
def program(tmp_path_factory):
  """(t, plans, states): asc-inc-cog seed 0 and des-uni-ang seed 1 in one program, fresh states."""
  plans = pack_plans(tmp_path_factory.mktemp("pack"))
  t = build_group(plans)
  return t, plans, init_group(t, plans, group_tasks(t, plans))


def test_a_runs_view_starts_steps_and_is_rewarded_as_its_own_tasks_environment():
  """The descent task's view of the ascent task's environment against the descent task's own: the
  same first state bit for bit (spawn on the landing, scene), then the same rewards and pitch-rate
  sums step by step (the ascent's own reward would sum the COG deviation, 0 off the stairs)."""
  asc, des = (load_config(task, TINY_SETTINGS) for task in (ASC, DES))
  assert packing_conflict(asc, des) is None
  view, alone = TrackedRobotEnv(asc).for_task(task_data(des, asc)), TrackedRobotEnv(des)

  def play(env):
    def episode(key):
      first = env.reset_at(key, jnp.float32(0.5), jnp.float32(1.0))

      def body(s, _):
        s = env.step(s, jnp.full(env.action_size, 0.8))
        return s, (s.reward, s.pipeline_state.signal_sum, s.pipeline_state.data.qpos)
      return first.pipeline_state, jax.lax.scan(body, first, None, length=4)[1]
    return jax.jit(episode)(jax.random.PRNGKey(3))

  (start, steps), (start_alone, steps_alone) = play(view), play(alone)
  assert all(np.array_equal(a, b) for a, b in zip(jax.tree_util.tree_leaves(start), jax.tree_util.tree_leaves(start_alone)))
  assert float(start.data.qpos[2]) > 0.2  # on the landing: a descent's spawn
  for got, want in zip(steps, steps_alone):
    np.testing.assert_allclose(np.asarray(got), np.asarray(want), rtol=1e-5, atol=1e-6)
  assert float(steps[1][-1]) > 0.01  # the pitch rate, summed: not the ascent's COG deviation


def test_each_run_of_a_program_of_several_tasks_starts_as_it_would_alone(program):
  t, plans, states = program
  for i, p in enumerate(plans):
    alone = jax.jit(build(p).learner.init)(jax.random.PRNGKey(p.seed))
    mine = run_slice(states, i)
    assert all(np.array_equal(np.asarray(a), np.asarray(b))
               for a, b in zip(jax.tree_util.tree_leaves(mine), jax.tree_util.tree_leaves(alone))), p.task


def test_runs_evaluated_each_by_its_own_evaluator_get_their_own_tasks(program, monkeypatch):
  """With reward.normalize_penalties (a batch statistic: no shared evaluation), each run's own Brax
  evaluator is built for its own task and seed."""
  from train.core import session
  from train.core.group import group_evaluations
  t, plans, _ = program

  def normalizing(p):
    cfg = dataclasses.replace(p.cfg, reward=dataclasses.replace(p.cfg.reward, normalize_penalties=True))
    return dataclasses.replace(p, cfg=cfg, preset=dataclasses.replace(p.preset, num_evals=2))
  built = []
  monkeypatch.setattr(session, "make_evaluator", lambda ti, seed: built.append((ti.plan.cfg.task, seed)))
  plans = [normalizing(p) for p in plans]
  shared, each = group_evaluations(dataclasses.replace(t, plan=plans[0]), plans, [p.cfg for p in plans])
  assert shared is None and built == [(ASC, 0), (DES, 1)]


def test_the_command_trains_each_task_with_each_seed_and_early_stop_and_records_each_run_as_its_own(tmp_path, capsys):
  """train.run --tasks A,B --seeds 0 --early-stops C,none (no --db), as a study packs two groups that
  differ only in their early stop: each run in the folder the study looks for (OUT/stop-<criterion>/
  <task>/s0), with its run.json, checkpoint and policy; each run's rows (the run, its statistics) in
  the database beside its task's folder, where `--resume OUT/...` finds them; the runs under the
  criterion (met at the first report) stop there, the others train every step."""
  from train.core.checkpoints import RunCheckpoints
  from train.db import ExperimentDB, default_path
  from train.study.spec import cells, pack_folders, pack_train_args, packs_of, study_from_dict
  group = {"algo": "sac", "preset": "cpu", "steps": [256], "set": list(TINY_SETTINGS), "pack_seeds": True,
           "pack_tasks": True, "hp": ["training_metrics_steps=64"]}
  spec = study_from_dict({"name": "p", "tasks": [ASC, DES], "seeds": [0], "baselines": [], "groups": [
      {**group, "name": "first", "early_stop": "return=-1000"}, {**group, "name": "whole"}]})
  [pack] = packs_of(cells(spec))
  out = tmp_path / "p"
  assert run.main([*pack_train_args(pack), "--probe-every", "0", "--out", str(out)]) == 0
  said = capsys.readouterr().out
  assert f"none {ASC} s0 [train]" in said and f"return=-1000 {DES} s0: 64 steps, stopped_early" in said
  for cell, member in zip(pack, pack_folders(pack)):
    folder = out / member
    record = json.load(open(folder / "run.json"))
    steps = 256 if cell.group == "whole" else 64
    assert (record["task"], record["config"]["task"]) == (cell.task, cell.task)
    assert RunCheckpoints(str(folder)).latest_step() == steps
    db = ExperimentDB(default_path(str(folder.parent)))
    assert [r["run_id"] for r in db.runs()] == [record["run_id"]] and db.stats(record["run_id"])  # its rows, its statistics
    assert db.run(record["run_id"])["status"] == ("done" if cell.group == "whole" else "stopped_early")
  _the_memory_check_reports_what_xla_plans_for_the_programs_states(pack_train_args(pack), capsys)
  _the_runs_evaluated_together_get_what_each_gets_alone([str(out / m) for m in pack_folders(pack)], capsys)


def _the_memory_check_reports_what_xla_plans_for_the_programs_states(args, capsys):
  """scripts/analysis/group_memory.py of the program the command just trained (its compiled step
  comes from the persistent cache): the update's arguments as XLA plans them are the runs' states as
  the project counts them (train.core.group.state_bytes); a program that cannot be is refused."""
  import importlib.util
  import re
  path = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "scripts", "analysis", "group_memory.py")
  spec = importlib.util.spec_from_file_location("group_memory", path)
  script = importlib.util.module_from_spec(spec)
  spec.loader.exec_module(script)
  assert script.main(args) == 0
  said = capsys.readouterr().out
  scale = {"GB": 1e9, "MB": 1e6}
  states, arguments = (float(x) * scale[unit] for x, unit in
                       re.findall(r"(?:states|arguments) ([\d.]+) ([GM]B)", said))
  assert "4 runs of 8 envs" in said and states > 0 and arguments == pytest.approx(states, rel=0.01, abs=6e3)
  assert script.main(["--tasks", f"{ASC},asc-hard", "--seeds", "0", *SAC_TINY]) == 2


def _the_runs_evaluated_together_get_what_each_gets_alone(folders, capsys):
  """`train.evaluate RUN RUN ... --await-runs` (a study's pack, started beside its training): the
  four runs' suites in one program, the two tasks as data, compiled before stdin named the runs and
  not traced again; each run's reports and trial rows its own (the database beside its folder), each
  as `train.evaluate RUN` of the run alone writes them (the same trials: floats within the vmap's
  rounding)."""
  from train import evaluate, evaluation
  from train.db import ExperimentDB, default_path
  from train.evaluation import report_path, suite_scenes
  # on the CPU one policy after another (vmapped_trials); here vmapped, as on a GPU, 3 policies a
  # call (EVAL_ENVS_PER_CALL: 9 environments): the second call the last run's, filled up with copies
  with pytest.MonkeyPatch.context() as mp:
    mp.setattr(evaluation, "vmapped_trials", lambda: True)
    mp.setattr(evaluation, "EVAL_ENVS_PER_CALL", 9)
    traced = await_runs_on_stdin(mp, folders)  # each rollout's trace: whether stdin had named the runs by then
    assert evaluate.main([*folders, "--suite", "--trials", "3", "--await-runs"]) == 0
  assert traced == [False]  # one program, traced (and compiled) ahead only
  said = capsys.readouterr().err
  assert "compiled the evaluation of 4 runs ahead (1 group(s))" in said and "evaluating 4 of 4 runs" in said
  assert "for 4 policies of 4 runs in one program, 3 a call (9 environments at most), its program compiled ahead" in said
  assert "restored 4 policies in " in said and "hardest: done in " in said  # where its time went
  scenes = suite_scenes(load_config(ASC))
  assert len(scenes) >= 4 and scenes == suite_scenes(load_config(DES))
  together = {(f, scene): json.load(open(report_path(f, scene, None))) for f in folders for scene in scenes}
  for f in folders:
    run_id = json.load(open(os.path.join(f, "run.json")))["run_id"]
    rows = ExperimentDB(default_path(os.path.dirname(f))).evals(run_id)
    assert sorted((r["scene"], r["trial"]) for r in rows) == sorted((sc, i) for sc in scenes for i in range(3))
  assert together[(folders[0], "hardest")]["per_trial"]["final_z"] != together[(folders[1], "hardest")]["per_trial"]["final_z"]
  # a descent run alone (not the task whose environment the program builds), then the runs together
  # one policy after another (the CPU's way: each run's figures bit for bit those it gets alone); the
  # two descent runs' figures of the vmapped calls (one in each call) are those
  assert evaluate.main([folders[1], "--suite", "--trials", "3"]) == 0
  alone = {scene: json.load(open(report_path(folders[1], scene, None))) for scene in scenes}
  assert evaluate.main([*folders, "--suite", "--trials", "3"]) == 0
  for f, scene in ((f, scene) for f in (folders[1], folders[3]) for scene in scenes):
    one_by_one = json.load(open(report_path(f, scene, None)))
    assert one_by_one["run_id"] == together[(f, scene)]["run_id"]
    if f == folders[1]:
      assert one_by_one["per_trial"] == alone[scene]["per_trial"]  # the same program: bit for bit
    for name in ("progress", "pitch_rate", "final_x", "final_z", "length"):
      np.testing.assert_allclose(together[(f, scene)]["per_trial"][name], one_by_one["per_trial"][name],
                                 rtol=1e-4, atol=1e-5, err_msg=f"{f} {scene} {name}")


@pytest.mark.parametrize("argv, words", [
    (["--tasks", f"{ASC},asc-hard", "--seeds", "0"], "differ in scene.riser"),  # another box pool
    (["--tasks", f"{ASC},{ASC}", "--seeds", "0"], "--tasks takes different task names"),
    (["--tasks", f"{ASC},{DES}"], "--tasks needs --seeds"),
    (["--tasks", f"{ASC},{DES}", "--task", ASC, "--seeds", "0"], "instead of --task"),
    (["--task", ASC, "--early-stops", "return,none"], "--early-stops needs --seeds"),
    (["--task", ASC, "--seeds", "0", "--early-stops", "return,return"], "--early-stops takes different criteria"),
    (["--task", ASC, "--seeds", "0", "--early-stops", "return,none", "--early-stop", "none"], "instead of --early-stop"),
    (["--task", ASC, "--seeds", "0", "--early-stops", "return,sometime"], "sometime"),
    (["--task", ASC, "--seeds", "0", "--early-stops", "return,return=0.5"], "two of them are one criterion")])
def test_tasks_one_program_cannot_hold_are_refused_in_one_line_before_anything_is_written(argv, words, tmp_path, capsys):
  assert run.main([*argv, *SAC_TINY, "--steps", "64", "--out", str(tmp_path / "g")]) == 2
  err = capsys.readouterr().err
  assert words in err and len(err.strip().splitlines()) == 1 and not os.path.exists(tmp_path / "g")

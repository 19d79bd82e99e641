"""Every command line answers bad input in one line with exit code 2 (no traceback), never
overwrites a fuller evaluation, and stays quiet when its reader goes away."""

import argparse
import json
import os
import subprocess
import sys

import numpy as np
import pytest

from mjx_tracks.envs.config import load_config
from mjx_tracks.metrics import EPISODE_NAMES
from train import evaluate
from train.db import ExperimentDB
from train.evaluate import main as evaluate_main
from train.run import main as run_main
from train.study.__main__ import main as study_main

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def _one_line_error(capsys, rc: int, *words: str) -> None:
  err = capsys.readouterr().err.strip()
  assert rc == 2 and err.startswith("error: ") and len(err.splitlines()) == 1 and "Traceback" not in err, err
  for w in words:
    assert w in err, err


def test_a_corrupt_or_foreign_run_json_is_one_line(tmp_path, capsys):
  (tmp_path / "run.json").write_text('{"run_id": "x", "task": ')
  _one_line_error(capsys, evaluate_main([str(tmp_path)]), "not readable JSON")
  (tmp_path / "run.json").write_text('[1, 2]')
  _one_line_error(capsys, evaluate_main([str(tmp_path)]), "not a run's record")


@pytest.mark.parametrize("argv, words", [
    (["--task", "asc-inc-cog", "--steps", str(10**30)], "--steps must be from 1 to"),
    (["--task", "asc-inc-cog", "--num-envs", str(10**12)], "--num-envs must be from 1 to"),
    (["--task", "asc-inc-cog", "--seed", "-3"], "--seed must be from 0 to"),
    (["--task", "asc-inc-cog", "--set", "scene.tread=[0.3"], "override scene.tread: not valid YAML"),
    (["--task", "asc-inc-cog", "--library", "brax", "--keep-checkpoints", "2"], "checkpoints, resume, probes, early stop or milestones (the parity reference); drop --keep-checkpoints"),
    (["--task", "asc-inc-cog", "--library", "brax", "--milestones", "5"], "--library brax trains with Brax's own"),
])
def test_train_run_refuses_out_of_range_numbers_and_broken_yaml_in_one_line(argv, words, tmp_path, capsys):
  _one_line_error(capsys, run_main([*argv, "--out", str(tmp_path / "r")]), words)


def test_train_evaluate_refuses_an_enormous_trial_count(tmp_path, capsys):
  (tmp_path / "run.json").write_text("{}")
  _one_line_error(capsys, evaluate_main([str(tmp_path), "--trials", str(10**9)]), "--trials must be from 1 to")


@pytest.mark.parametrize("text, overrides, words", [
    ("name: [unclosed", [], "not valid YAML"),
    ("- just\n- a list", [], "top level must be a mapping"),
    ("name: t\ntasks: [nope]\nseeds: [0]\ngroups: [{name: g, algo: ppo, preset: cpu, steps: [1]}]\n"
     "compare: [[nope, asc-inc-cog]]", [], "unknown task 'nope'"),
    ("name: t", ["seeds=[0"], "override seeds: not valid YAML"),
])
def test_study_files_and_overrides_that_do_not_parse_are_one_line(text, overrides, words, tmp_path, capsys):
  path = tmp_path / "s.yaml"
  path.write_text(text)
  sets = [a for item in overrides for a in ("--set", item)]
  _one_line_error(capsys, study_main([str(path), "--plan", *sets]), words)


def test_an_evaluation_of_fewer_trials_never_overwrites_a_fuller_report(tmp_path, capsys):
  db = ExperimentDB(str(tmp_path / "experiments.sqlite"))
  db.start("r", "asc-inc-cog", "ppo", "cpu", 0, {}, str(tmp_path / "r"), 100)
  (tmp_path / "r").mkdir()
  meta = {"run_id": "r", "task": "asc-inc-cog", "algo": "ppo"}

  def write(trials: int) -> str:
    args = argparse.Namespace(run_dir=str(tmp_path / "r"), trials=trials, eps=1.0, checkpoint=None, out=None,
                              db=db.path, argv=["r", "--trials", str(trials)])
    figures = {k: np.full(trials, 0.5) for k in EPISODE_NAMES}
    return evaluate._write_report(args, args.run_dir, meta, "hardest", None, 100, figures)

  full = write(100)
  assert full.endswith("eval-hardest.json") and len(db.eval_groups("r")[("hardest", None)]) == 100
  small = write(1)
  assert small.endswith("eval-hardest.1-trials.json") and "kept" in capsys.readouterr().err
  assert json.load(open(full))["trials"] == 100 and len(db.eval_groups("r")[("hardest", None)]) == 100
  assert write(200) == full and json.load(open(full))["trials"] == 200  # a fuller one replaces it


def test_the_database_export_is_quiet_when_its_reader_stops(tmp_path):
  db = ExperimentDB(str(tmp_path / "experiments.sqlite"))
  db.start("r", "asc-inc-cog", "ppo", "cpu", 0, {}, str(tmp_path / "r"), 100)
  for step in range(1, 2_501):  # more than a pipe holds (64 KiB)
    db.log_stats("r", {"step": step, "source": "train"}, {})
  cmd = f"{sys.executable} -m train.db --db {db.path} export r --csv | head -2"
  out = subprocess.run(["bash", "-c", cmd], capture_output=True, text=True, cwd=ROOT, timeout=120)
  assert len(out.stdout.splitlines()) == 2 and "Error" not in out.stderr, out.stderr


def test_the_compile_estimate_is_the_longest_compilation_seen(tmp_path, monkeypatch):
  """A partial cache hit (11 s) after a cold compile (42 s) must not make the next estimate 11 s."""
  from mjx_tracks import compile_cache
  monkeypatch.setattr(compile_cache, "cache_dir", lambda: tmp_path)
  for seconds in (42.0, 11.0, 3.0):
    compile_cache.record_compile_seconds("ppo/cpu", seconds)
  assert compile_cache.last_compile_seconds("ppo/cpu") == 42.0


def test_the_compilation_log_names_the_longest_compilations(tmp_path):
  """MJX_TRACKS_COMPILE_LOG's lines (a process's own JAX log records), read back by
  compile_cache.longest_compilations: the jitted function's compilation among them, longest first."""
  from mjx_tracks import compile_cache
  log = str(tmp_path / "compile.log")
  code = ("from mjx_tracks import compile_cache; compile_cache.log_compilations({!r}); import jax, jax.numpy as jnp;"
          "jax.jit(lambda x: jnp.sin(x) * 2).lower(jnp.ones(3)).compile(); jax.jit(jnp.cos)(jnp.ones(2))").format(log)
  subprocess.run([sys.executable, "-c", code], check=True, env={**os.environ, "JAX_PLATFORMS": "cpu"}, timeout=120)
  longest = compile_cache.longest_compilations(log, n=50)
  assert {"jit(<lambda>)", "jit(cos)"} <= {what for _, what in longest}
  assert [s for s, _ in longest] == sorted((s for s, _ in longest), reverse=True) and all(s >= 0 for s, _ in longest)
  assert len(compile_cache.longest_compilations(log, n=1)) == 1
  assert compile_cache.longest_compilations(str(tmp_path / "none.log")) == []


def test_train_evaluate_takes_several_scenes_each_once_and_refuses_them_beside_the_suite():
  cfg = load_config("nav")
  args = evaluate.parser().parse_args(["r", "--scene", "nav/hallway", "--scene", "nav/zigzag", "--scene", "nav/hallway"])
  assert evaluate._jobs(args, cfg, "r")[0] == ["nav/hallway", "nav/zigzag"]  # argparse once kept only the last
  assert evaluate._jobs(evaluate.parser().parse_args(["r"]), load_config("asc-inc-cog"), "r")[0] == ["hardest"]
  with pytest.raises(ValueError, match="give one of them"):
    evaluate._jobs(evaluate.parser().parse_args(["r", "--scene", "uniform", "--suite"]), cfg, "r")
  with pytest.raises(ValueError, match="one scene"):
    evaluate._jobs(evaluate.parser().parse_args(["r", "--scene", "uniform", "--scene", "nav/zigzag", "--out", "x"]), cfg, "r")


def test_a_trained_run_is_evaluated_on_held_out_scenes_added_since_but_never_on_another_task(capsys):
  """A run recorded before `evaluation.held_out_nav` entries had a length (12 m then) loads as it
  trained; `--set evaluation.*` adds what it is evaluated on; any other key is one line, exit 2."""
  run_dir = os.path.join(ROOT, "results", "studies", "nav", "runs", "ppo_nav_6000000_s0")  # trained 2026-11-26
  raw = json.load(open(os.path.join(run_dir, "run.json")))["config"]
  assert all("length" not in h for h in raw["evaluation"]["held_out_nav"])
  assert [h.length for h in evaluate.recorded_config(raw).evaluation.held_out_nav] == [12.0, 12.0]
  longer = evaluate.recorded_config(raw, ["evaluation.held_out_nav=[{name: long-area, gap: [1.0, 2.0], "
                                          "floor_obstacles: 0, length: 18.0}]"])
  assert [(h.name, h.length) for h in longer.evaluation.held_out_nav] == [("long-area", 18.0)]
  assert "held-out/long-area" in evaluate.suite_scenes(longer)
  _one_line_error(capsys, evaluate_main([run_dir, "--set", "reward.goal_bonus=3"]), "only evaluation.* keys")


def test_train_evaluate_refuses_what_takes_one_run_beside_several_runs(capsys, tmp_path):
  for extra in (["--out", "x.json"], ["--checkpoint"], ["--video", "v.gif"], ["--baseline", "zero", "--task", "asc-inc-cog"]):
    _one_line_error(capsys, evaluate.main([str(tmp_path / "a"), str(tmp_path / "b"), *extra]), "take one RUN_DIR")
    # nor beside a training (a study's pack), even for one run, before anything is waited for
    _one_line_error(capsys, evaluate.main([str(tmp_path / "a"), *extra, "--await-runs"]), "drop --baseline")
  _one_line_error(capsys, evaluate.main(["--await-runs"]), "needs the RUN_DIRs")


def test_a_resume_refuses_fixed_options_naming_those_it_takes():
  """train.core.plan's RESUME_FREE: options of train.run, none of them fixed, all named by the refusal."""
  from train.core.plan import RESUME_FIXED, RESUME_FREE, RunError, plan_run
  from train.run import parser
  dests = {a.dest for a in parser()._actions}  # noqa: SLF001
  assert set(RESUME_FREE) <= dests and not set(RESUME_FREE) & set(RESUME_FIXED)
  with pytest.raises(RunError) as refused:
    plan_run(parser().parse_args(["--resume", "runs/x", "--seed", "3"]))
  assert "drop --seed (only --steps, --db, --checkpoint-every, --keep-checkpoints, --compile-ahead and " \
         "--split-update may be given)" in str(refused.value)

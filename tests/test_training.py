"""Training end to end on the CPU: a tiny PPO run, resume, export -> load -> act, evaluation
report, experiment database, bad input (SAC: test_training_sac.py)."""

import datetime
import glob
import json
import multiprocessing
import os
import re
import shutil
import subprocess
import sys
import time

import jax
import numpy as np
import pytest

from helpers import (HELD_OUT, TINY_SETTINGS, TRAIN_TINY, await_runs_on_stdin, checkpoint_steps, run_id,
                     start_training, wait_for)
from train import db as dbmod
from train import evaluate, run
from train.core.checkpoints import RunCheckpoints


def test_the_main_command_ends_saying_what_it_made_and_what_to_run_next(ppo_run):
  out, database = ppo_run
  said = open(os.path.join(os.path.dirname(out), "ppo.stdout")).read()
  tail = said[said.index("\ndone: 2,048 steps"):]
  assert f"made: {out}/ with policy/" in tail and database in tail
  assert f"python -m train.evaluate {out} --scene hardest" in tail and "python -m train.server" in tail
  assert f"load_policy('{out}/policy')" in tail and '"reason"' not in said  # no JSON blob


def test_ppo_run_writes_checkpoint_database_rows_and_events(ppo_run):
  out, database = ppo_run
  steps = RunCheckpoints(out).mgr.all_steps()
  assert steps and max(steps) == 2048
  assert os.path.exists(os.path.join(out, "policy", "policy.json"))
  assert glob.glob(os.path.join(out, "tb", "events.out.tfevents.*"))
  d = dbmod.ExperimentDB(database)
  row = d.run(run_id(out))
  assert row["status"] == "done" and row["task"] == "asc-inc-cog" and row["algo"] == "ppo"
  stats = d.stats(row["run_id"])
  assert {s["source"] for s in stats} == {"train", "probe"}  # no Brax evaluator in the cpu preset
  train_rows = [s for s in stats if s["source"] == "train"]
  assert len(train_rows) >= 2 and all(s["return_mean"] is not None for s in train_rows)
  assert any(s["eps"] is not None for s in train_rows)


def test_the_database_holds_the_compile_time_and_training_rates_the_command_printed(ppo_run):
  """What benchmarks read of a run (train.bench.runs), from its database: the training step's
  compile seconds and each training report's steps/s, as the run printed them (rounded as printed)."""
  import re
  from train.bench import runs
  out, database = ppo_run
  said = open(os.path.join(os.path.dirname(out), "ppo.stdout")).read()
  (printed_compile,) = re.findall(r"compiled in ([0-9,]+) s", said)
  printed_rates = [float(x.replace(",", "")) for x in re.findall(r"^\[train\].*?([0-9,]+) steps/s", said, re.M)]
  compiled = runs.compile_seconds(database)
  assert compiled is not None and abs(compiled - float(printed_compile.replace(",", ""))) <= 0.501
  started = [e["time"] for e in dbmod.ExperimentDB(database).events(run_id(out)) if e["event"] == "started"]
  assert runs.compiled_at(database) >= datetime.datetime.fromisoformat(started[0]).timestamp()  # training from then
  rates = runs.training_rates(database)
  assert len(rates) == len(printed_rates) >= 2 and [r["step"] for r in rates] == sorted(r["step"] for r in rates)
  assert [round(r["steps_per_s"]) for r in rates] == printed_rates
  assert runs.steady_rate(rates) == np.median([r["steps_per_s"] for r in rates[1:]])
  assert runs.steady_rate(rates[:1]) is None
  with pytest.raises(FileNotFoundError, match="no run database"):
    runs.training_rates(database + ".missing")


def test_a_restore_target_is_the_new_networks_shapes_with_no_program_compiled():
  """NetworkSpec.policy_params_target, which restores fill: the structure, shapes and dtypes of a new
  network's parameters, with no program compiled (an eager network init compiled its small
  operations in each process that restored a policy: ~2.5 s of a `train.evaluate` on a CPU,
  2026-11-29). The listener sees init_policy_params compile, so the event it watches exists."""
  from jax import monitoring
  from train.core.networks import NetworkSpec
  compiled = []
  listener = lambda name, secs, **kw: compiled.append(name) if name.endswith("backend_compile_duration") else None  # noqa: E731
  monitoring.register_event_duration_secs_listener(listener)
  try:
    spec = NetworkSpec("ppo", 13, 3, (5,), (7,))  # shapes no other test compiles
    target = spec.policy_params_target()
    assert not compiled
    real = spec.init_policy_params()
    assert compiled  # eager: its operations compiled here, seen by the listener
  finally:
    monitoring.unregister_event_duration_listener(listener)
  assert jax.tree_util.tree_structure(target) == jax.tree_util.tree_structure(real)
  assert [(t.shape, t.dtype) for t in jax.tree_util.tree_leaves(target)] == \
      [(np.shape(r), jax.numpy.asarray(r).dtype) for r in jax.tree_util.tree_leaves(real)]  # a float: its dtype in JAX


def test_export_load_act_reproduces_the_checkpointed_policy(ppo_run):
  from flax import serialization
  from train.core.networks import NetworkSpec
  from train.core.policy import load_policy
  import mjx_tracks
  out, _ = ppo_run
  raw, meta = RunCheckpoints(out).restore()
  spec = NetworkSpec.from_json(meta["network"])
  params = serialization.from_state_dict(spec.policy_params_target(), {"0": raw["0"], "1": raw["1"]})
  reference = spec.make_inference_fn()(params, deterministic=True)
  act = load_policy(os.path.join(out, "policy"))
  env = mjx_tracks.load("asc-inc-cog", TINY_SETTINGS)
  obs = jax.jit(jax.vmap(env.reset))(jax.random.split(jax.random.PRNGKey(0), 5)).obs  # one program, not ~250 eager ones
  a = np.asarray(act(obs))
  np.testing.assert_allclose(a, np.asarray(reference(obs, jax.random.PRNGKey(1))[0]), atol=1e-6)
  assert a.shape == (5, env.action_size) and np.abs(a).max() <= 1.0


def test_resume_continues_from_the_saved_step_and_curriculum(ppo_run, tmp_path, capsys):
  out, database = ppo_run
  copy = str(tmp_path / "resumed")
  shutil.copytree(out, copy)
  ck = RunCheckpoints(copy)
  before_step = ck.latest_step()
  _, before = ck.restore()
  assert run.main(["--resume", copy, "--steps", str(before_step + 1024), "--db", database]) == 0
  assert f"from its checkpoint at step {before_step:,} ({copy}/checkpoints/{before_step})" in capsys.readouterr().out
  ck = RunCheckpoints(copy)
  assert ck.latest_step() > before_step
  _, after = ck.restore()
  c0, c1 = before["global"]["curriculum"], after["global"]["curriculum"]
  assert c1["finished"] > c0["finished"] > 0  # the curriculum kept counting from where it was
  d = dbmod.ExperimentDB(database)
  rid = run_id(copy)
  steps = [(r["source"], r["step"]) for r in d.stats(rid)]
  assert len(steps) == len(set(steps))  # the resumed part replaced, not duplicated, its rows
  walls = [r["wall_s"] for r in d.stats(rid)]
  assert walls == sorted(walls)  # wall time accumulates across the resume
  events = [e["event"] for e in d.events(rid)]
  assert events[0] == "started" and "resumed" in events and events[-1] == "finished"
  assert "checkpoint" in events and d.run(rid)["total_steps"] == before_step + 1024


def _corrupt(step_dir: str) -> None:
  """Overwrites every file of a checkpoint's state with garbage of the same size."""
  for root, _, files in os.walk(os.path.join(step_dir, "state")):
    for name in files:
      path = os.path.join(root, name)
      with open(path, "r+b") as f:
        f.write(b"\xff" * max(os.path.getsize(path), 1))


def test_sigkill_then_resume_continues_bit_for_bit_past_a_corrupt_checkpoint(ppo_run, tmp_path, capsys):
  """A run checkpointing after every update is SIGKILLed once it has two checkpoints past 0; its
  newest is damaged; the resume falls back to the one before, and its next updates give exactly
  the state of the uninterrupted run (the fixture, same seed) at 2048 steps (512 per update)."""
  reference, database = ppo_run
  out = str(tmp_path / "killed")
  proc = start_training([*TRAIN_TINY, "--steps", "1000000", "--checkpoint-every", "0", "--out", out,
                         "--db", database], str(tmp_path / "log"))
  wait_for(lambda: len([s for s in checkpoint_steps(out) if s > 0]) >= 2, proc, 300, "two checkpoints")
  proc.kill()
  proc.wait(30)
  steps = checkpoint_steps(out)
  assert steps[-1] < 2048, steps
  _corrupt(os.path.join(out, "checkpoints", str(steps[-1])))
  assert run.main(["--resume", out, "--steps", "2048", "--db", database]) == 0
  err = capsys.readouterr().err
  assert f"checkpoint {steps[-1]:,} in" in err and f"falling back to checkpoint {steps[-2]:,}" in err
  resumed = RunCheckpoints(out).arrays(2048)
  uninterrupted = RunCheckpoints(reference).arrays(2048)
  assert resumed.keys() == uninterrupted.keys() and len(resumed) > 100
  for k in resumed:
    np.testing.assert_array_equal(np.asarray(resumed[k]), np.asarray(uninterrupted[k]), err_msg=k)
  events = [e["event"] for e in dbmod.ExperimentDB(database).events(run_id(out))]
  assert events[0] == "started" and "crashed" in events and events[-2:] == ["checkpoint", "finished"]


def test_evaluation_writes_a_valid_report_equal_to_the_in_training_probe(ppo_run, tmp_path, capsys):
  """`train.evaluate --scene hardest` of the exported policy runs the very trials of the
  in-training hardest probe (train.core.probe) of the final state: the same figures; it says how
  long the scene took."""
  out, database = ppo_run
  report = str(tmp_path / "eval.json")
  t0 = time.monotonic()
  assert evaluate.main([out, "--scene", "hardest", "--out", report, "--db", database]) == 0
  took = re.search(r"^hardest: done in ([\d.]+) s \((\d+) s since the process started\)$", capsys.readouterr().err, re.M)
  assert took and float(took.group(1)) <= time.monotonic() - t0 + 0.1 and int(took.group(2)) >= float(took.group(1)) - 1
  with open(report) as f:
    r = json.load(f)
  assert r["trials"] == evaluate.EVAL_TRIALS and r["scene"] == "hardest"
  for k in ("progress", "success", "cog_deviation", "pitch_rate", "tipped_over", "length"):
    assert set(r["metrics"][k]) == {"mean", "std"} and len(r["per_trial"][k]) == evaluate.EVAL_TRIALS
  assert 0.0 <= r["metrics"]["progress"]["mean"] <= 1.0 + 1e-6
  assert len(dbmod.ExperimentDB(database).evals(run_id(out))) == evaluate.EVAL_TRIALS
  probe = [row for row in dbmod.ExperimentDB(database).stats(run_id(out)) if row["source"] == "probe"]
  assert [row["step"] for row in probe] == [2048]
  for column, figure in (("progress_mean", "progress"), ("success_rate", "success"),
                         ("pitch_rate_mean", "pitch_rate"), ("tipped_rate", "tipped_over")):
    assert probe[0][column] == pytest.approx(r["metrics"][figure]["mean"], abs=1e-6), column


def test_the_evaluations_process_age_is_the_time_since_its_process_started():
  """train.evaluate's 'since the process started' (from /proc) against the parent's clock: a
  process that sleeps 1 s, then imports the module and asks."""
  code = "import time; time.sleep(1.0); from train.evaluate import _process_age; print(_process_age())"
  t0 = time.monotonic()
  said = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                        cwd=os.path.dirname(os.path.dirname(os.path.abspath(__file__)))).stdout
  assert 1.0 <= float(said.split()[-1]) <= time.monotonic() - t0 + 0.02  # /proc's clock ticks: 0.01 s


def test_bad_input_fails_with_one_line_and_overwrites_nothing(ppo_run, tmp_path, capsys):
  out, _ = ppo_run
  assert run.main(["--task", "flying", "--out", str(tmp_path / "x")]) == 2
  assert "unknown task 'flying'" in capsys.readouterr().err
  assert run.main(["--task", "defaults", "--out", str(tmp_path / "x")]) == 2
  assert "unknown task 'defaults'" in capsys.readouterr().err
  assert run.main(["--task", "asc-inc-cog", "--steps", "0", "--out", str(tmp_path / "x")]) == 2
  assert "--steps must be from 1 to" in capsys.readouterr().err
  assert not os.path.exists(str(tmp_path / "x"))
  assert run.main(["--task", "asc-inc-cog", "--set", "reward.cog_scal=1", "--out", str(tmp_path / "y")]) == 2
  assert "reward.cog_scal: unknown key" in capsys.readouterr().err
  for bad, words in ((["--early-stop", "speed"], "one of return, success"),
                     (["--probe-every", "-1"], "--probe-every must be >= 0"),
                     (["--early-stop", "success", "--probe-every", "0"], "needs the probe; drop --probe-every 0")):
    assert run.main(["--task", "asc-inc-cog", *bad, "--out", str(tmp_path / "z")]) == 2
    assert words in capsys.readouterr().err
  assert not os.path.exists(str(tmp_path / "z"))
  before = open(os.path.join(out, "run.json")).read()
  assert run.main(["--task", "asc-inc-cog", "--out", out]) == 2
  assert "already holds run" in capsys.readouterr().err
  assert open(os.path.join(out, "run.json")).read() == before
  assert run.main(["--resume", str(tmp_path)]) == 2
  assert "no run.json" in capsys.readouterr().err
  # a run directory whose checkpoints are gone or damaged
  broken = str(tmp_path / "broken")
  shutil.copytree(out, broken)
  shutil.rmtree(os.path.join(broken, "checkpoints"))
  assert run.main(["--resume", broken, "--db", str(tmp_path / "db2.sqlite")]) == 2
  assert "no checkpoint" in capsys.readouterr().err
  assert evaluate.main([str(tmp_path), "--trials", "2"]) == 2


def test_a_failed_resume_touches_no_record(ppo_run, tmp_path, capsys):
  """A finished run, options that would change it, and a run whose checkpoints are all damaged."""
  out, database = ppo_run
  before = open(os.path.join(out, "run.json")).read()
  status = dbmod.ExperimentDB(database).run(run_id(out))["status"]
  assert run.main(["--resume", out, "--db", database]) == 2  # already finished
  err = capsys.readouterr().err
  assert "is finished" in err and f"--resume {out} --steps N" in err
  assert run.main(["--resume", out, "--task", "asc-uni-cog", "--set", "reward.cog_scale=1", "--db", database]) == 2
  assert "drop --task, --set" in capsys.readouterr().err
  assert open(os.path.join(out, "run.json")).read() == before
  assert dbmod.ExperimentDB(database).run(run_id(out))["status"] == status == "done"
  # every checkpoint unreadable: one line per damaged checkpoint, one error, no record touched
  damaged = str(tmp_path / "damaged")
  shutil.copytree(out, damaged)
  for step in checkpoint_steps(damaged):
    _corrupt(os.path.join(damaged, "checkpoints", str(step)))
  events = len(dbmod.ExperimentDB(database).events(run_id(out)))
  assert run.main(["--resume", damaged, "--steps", "4096", "--db", database]) == 2
  err = capsys.readouterr().err
  assert "error: --resume" in err and "no readable checkpoint" in err
  assert "Traceback" not in err and "Event loop is closed" not in err
  assert open(os.path.join(damaged, "run.json")).read() == before
  assert len(dbmod.ExperimentDB(database).events(run_id(out))) == events


def test_the_suite_evaluates_every_scene_at_every_milestone_with_its_own_policy(ppo_run, tmp_path):
  """--suite --milestones: hardest, uniform and the held-out staircase for the policy exported at
  1,024 steps and the final one; each report names its budget and policy step; the database gets
  every trial once per (scene, budget), also when evaluated again."""
  from train.core.policy import load_policy_info
  out, _ = ppo_run
  run_dir, database = str(tmp_path / "run"), str(tmp_path / "db.sqlite")
  shutil.copytree(out, run_dir)
  dbmod.ExperimentDB(database).import_runs(os.path.join(os.path.dirname(out), "db.sqlite"))
  assert load_policy_info(os.path.join(run_dir, "milestones", "1024"))["step"] == 1024
  # 2 trials: every scene at every milestone is what it checks, not their figures
  assert evaluate.main([run_dir, "--suite", "--milestones", "--trials", "2", "--db", database]) == 0
  # again, as a study's pack evaluates beside its training (--await-runs): the programs of the
  # milestone's policy and the final one traced before stdin names the run, never after
  with pytest.MonkeyPatch.context() as mp:
    traced = await_runs_on_stdin(mp, [run_dir])
    assert evaluate.main([run_dir, "--scene", "hardest", "--milestones", "--trials", "2", "--db", database,
                          "--await-runs"]) == 0
  assert traced == [False]  # one program (one task), for both policies
  scenes = ["hardest", "uniform", f"held-out/{HELD_OUT}"]
  for scene in scenes:
    for budget, step in ((1024, 1024), (None, 2048)):
      r = json.load(open(evaluate.report_path(run_dir, scene, budget)))
      assert (r["scene"], r["budget"], r["policy_step"], r["trials"]) == (scene, budget, step, 2)
  rows = dbmod.ExperimentDB(database).evals(run_id(out))
  assert sorted({(e["scene"], e["budget"]) for e in rows}, key=str) == sorted(
      {(s, b) for s in scenes for b in (1024, None)}, key=str)
  assert len(rows) == len(scenes) * 2 * 2  # hardest evaluated twice: replaced, not duplicated
  held = json.load(open(evaluate.report_path(run_dir, f"held-out/{HELD_OUT}", None)))["per_trial"]
  assert held["final_x"][0] != held["final_x"][1]  # one fixed staircase, but each trial's start varies: samples


def test_a_killed_run_is_evaluated_from_its_checkpoints(ppo_run, tmp_path, capsys):
  out, database = ppo_run
  killed = str(tmp_path / "killed")
  shutil.copytree(out, killed)
  shutil.rmtree(os.path.join(killed, "policy"))  # killed before the export
  report = str(tmp_path / "eval.json")
  assert evaluate.main([killed, "--trials", "2", "--db", database, "--out", report]) == 2
  assert "no policy.json" in capsys.readouterr().err
  assert evaluate.main([killed, "--checkpoint", "--trials", "2", "--db", database, "--out", report]) == 0
  r = json.load(open(report))
  assert r["checkpoint"] and r["policy_step"] == RunCheckpoints(killed).latest_step()
  first = min(RunCheckpoints(killed).mgr.all_steps())
  assert evaluate.main([killed, "--checkpoint", str(first), "--trials", "2", "--db", database, "--out", report]) == 0
  assert json.load(open(report))["policy_step"] == first
  assert evaluate.main([killed, "--checkpoint", "999999", "--trials", "2", "--db", database]) == 2
  assert "no checkpoint 999999" in capsys.readouterr().err


def test_db_cli_lists_with_a_header_and_takes_run_directories(ppo_run, capsys):
  out, database = ppo_run
  assert dbmod.main(["--db", database, "list"]) == 0
  lines = capsys.readouterr().out.splitlines()
  assert lines[0].split()[:3] == ["run", "task", "algo"] and any(out in line for line in lines[1:])
  assert dbmod.main(["--db", database, "show", out]) == 0
  shown = capsys.readouterr().out
  assert run_id(out) in shown and "event" in shown and "checkpoint" in shown
  assert dbmod.main(["--db", database, "export", out, "--csv"]) == 0
  assert capsys.readouterr().out.startswith("step,wall_s")


def test_the_cpu_default_is_the_preset_that_solves_the_flagship_task():
  """Without --preset, a PPO run on the CPU gets `laptop` (measured: results/first_run/), SAC the
  small `cpu`; each default exists."""
  from train.core.plan import default_preset
  from train.core.presets import get_preset
  assert jax.default_backend() == "cpu"
  assert default_preset("ppo") == "laptop" and default_preset("sac") == "cpu"
  p = get_preset("ppo", "laptop")
  assert p.num_timesteps % (p.batch_size * p.num_minibatches * p.unroll_length) == 0  # whole updates
  assert get_preset("sac", default_preset("sac")).num_envs >= 1


def test_run_ids_started_in_the_same_second_differ():
  ids = {run.new_run_id("asc-inc-cog", "ppo", 0) for _ in range(50)}
  assert len(ids) == 50 and all(i.startswith("asc-inc-cog-ppo-s0-") for i in ids)


def test_importing_the_package_prints_no_warp_noise():
  import subprocess
  import sys
  out = subprocess.run([sys.executable, "-c", "import mjx_tracks"], capture_output=True, text=True,
                       env={**os.environ, "JAX_PLATFORMS": "cpu"}, timeout=120)
  assert out.returncode == 0 and "warp" not in out.stdout + out.stderr


def _write_rows(path, run_id, n):
  d = dbmod.ExperimentDB(path)
  for i in range(n):
    d.log_stats(run_id, {"step": i, "return_mean": float(i)}, {"x": float(i)})


def test_concurrent_writers_do_not_corrupt_the_database(tmp_path):
  path = str(tmp_path / "shared.sqlite")
  d = dbmod.ExperimentDB(path)
  for rid in ("a", "b"):
    d.start(rid, "asc-inc-cog", "ppo", "cpu", 0, {}, str(tmp_path), 10)
  ctx = multiprocessing.get_context("spawn")
  procs = [ctx.Process(target=_write_rows, args=(path, rid, 150)) for rid in ("a", "b")]
  for p in procs:
    p.start()
  for p in procs:
    p.join(60)
  assert all(p.exitcode == 0 for p in procs)
  assert len(d.stats("a")) == 150 and len(d.stats("b")) == 150


def test_a_run_whose_process_died_reads_crashed(tmp_path):
  d = dbmod.ExperimentDB(str(tmp_path / "c.sqlite"))
  d.start("dead", "asc-inc-cog", "ppo", "cpu", 0, {}, str(tmp_path), 10)
  with d._conn() as c:
    c.execute("UPDATE experiments SET pid=? WHERE run_id='dead'", (2**22 + 12345,))
  assert d.run("dead")["status"] == "crashed"
  assert dbmod.main(["--db", str(tmp_path / "c.sqlite"), "list"]) == 0
  assert dbmod.main(["--db", str(tmp_path / "c.sqlite"), "show", "nope"]) == 2


def test_a_resume_drops_the_rows_past_its_checkpoint_and_records_the_crash(tmp_path):
  d = dbmod.ExperimentDB(str(tmp_path / "r.sqlite"))
  d.start("r", "asc-inc-cog", "ppo", "cpu", 0, {}, str(tmp_path), 10)
  for step in range(1, 6):
    d.log_stats("r", {"step": step, "wall_s": 10.0 * step}, {})
  d.set_checkpoint("r", str(tmp_path), 3)
  with d._conn() as c:  # the process died: its pid is gone, the row still says running
    c.execute("UPDATE experiments SET pid=? WHERE run_id='r'", (2**22 + 12345,))
  assert d.wall_offset("r", 3) == 30.0
  d.start("r", "asc-inc-cog", "ppo", "cpu", 0, {}, str(tmp_path), 20, resume_step=3)
  assert [r["step"] for r in d.stats("r")] == [1, 2, 3]
  assert [(e["event"], e["step"]) for e in d.events("r")] == [
      ("started", 0), ("checkpoint", 3), ("crashed", None), ("resumed", 3)]
  assert d.run("r")["total_steps"] == 20
  d.finish("r", "interrupted", {}, 4)
  assert d.events("r")[-1]["event"] == "interrupted"


def test_a_database_from_before_row_sources_gains_the_column(tmp_path):
  """Databases written before stats rows had a source open, and take new rows with one."""
  import sqlite3
  path = str(tmp_path / "old.sqlite")
  old_schema = dbmod.SCHEMA.replace(", metrics_json TEXT, source TEXT", ", metrics_json TEXT")
  assert old_schema != dbmod.SCHEMA
  with sqlite3.connect(path) as c:
    c.executescript(old_schema)
  d = dbmod.ExperimentDB(path)
  d.start("r", "asc-inc-cog", "ppo", "cpu", 0, {}, str(tmp_path), 10)
  d.log_stats("r", {"step": 1, "success_rate": 1.0, "source": "hardest"}, {})  # the probe's name before
  assert [(s["step"], s["source"]) for s in dbmod.ExperimentDB(path).stats("r")] == [(1, "probe")]


def test_a_run_made_from_the_dashboard_form_trains_for_real(ppo_run, tmp_path):
  """The system Chromium fills the dashboard's form with this file's tiny task and launches it; the
  server's launcher runs the real train.run and train.evaluate on a local Dask cluster; the run
  reaches done and its page draws its training curve. No evaluation suite (0 trials; the stand-in
  tests cover it); here, after this file's runs, the compilation cache holds its training step."""
  if os.environ.get("MJX_TRACKS_NO_BROWSER") == "1":
    pytest.skip("MJX_TRACKS_NO_BROWSER=1")
  from distributed import Client, LocalCluster
  from helpers import chromium
  from playwright.sync_api import sync_playwright
  from train.server.app import create_app
  from train.server.background import serve_in_thread
  from train.server.launcher import Launcher
  from train.server.settings import Settings
  settings = Settings(str(tmp_path / "experiments.sqlite"), str(tmp_path))
  with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, resources={"cpu": 1},
                    dashboard_address=":0") as cluster, Client(cluster) as client, sync_playwright() as p:
    launcher = Launcher(settings.db, settings.runs_root, client, ("cpu",), poll_s=0.2).start()
    base, stop = serve_in_thread(create_app(settings, launcher))
    try:
      page = p.chromium.launch(executable_path=chromium(), headless=True, args=["--no-sandbox"]).new_page()
      page.goto(f"{base}/new")
      page.wait_for_selector("#f-episode--max_steps")
      tiny = [("#f-" + key.replace(".", "--"), value) for key, value in (s.split("=", 1) for s in TINY_SETTINGS)]
      for field, value in (("#steps", "512"), ("#eval_trials", "0"), *tiny):  # one update
        page.fill(field, value)
      page.click("#launch")
      page.wait_for_function("document.getElementById('result').textContent.startsWith('queued')")
      page.goto(f"{base}/queue")
      page.wait_for_function("[...document.querySelectorAll('#rows tr')].some(r => /done|failed/.test(r.textContent))",
                             timeout=300_000)
      (launch,) = dbmod.ExperimentDB(settings.db).launches()
      assert launch["status"] == "done", launch["error"]
      (run,) = dbmod.ExperimentDB(settings.db).runs()
      assert run["status"] == "done" and run["total_steps"] == 512
      page.goto(f"{base}/runs/{run['run_id']}")
      page.wait_for_function("document.querySelector('.chart') && document.querySelector('.chart').data[0].x.length > 0")
      assert not dbmod.ExperimentDB(settings.db).evals(run["run_id"])  # 0 evaluation trials: no suite
    finally:
      stop()
      launcher.stop()

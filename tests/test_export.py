"""ONNX export (train.export) of the session's PPO run: onnxruntime against the JAX policy on 1,000
observations, the layout metadata against the env's, a failed check writes nothing; onnxruntime
drives the simulator (train.onnx_drive). The robustness suite of train.evaluate on a baseline."""

import json
import os

import numpy as np


def test_the_onnx_policy_matches_the_jax_policy_and_carries_its_layout(ppo_run, tmp_path, capsys):
  from mjx_tracks.envs.config import from_dict
  from mjx_tracks.envs.task_env import TrackedRobotEnv, observation_names
  from train import export
  run_dir, _ = ppo_run
  path = str(tmp_path / "policy.onnx")
  assert export.main([run_dir, "--onnx", path]) == 0
  meta = export.read_metadata(path)
  assert meta["parity"]["observations"] == 1000 and meta["parity"]["max_abs_difference"] <= 1e-5
  # parity again, independently of the command: the file's actions against the JAX policy's
  fn, spec, params, _ = export.policy_function(run_dir)
  obs = export.parity_observations(params, 1000, seed=7)
  got = export.onnx_policy(path)(obs)
  np.testing.assert_allclose(got, np.asarray(fn(obs)), atol=1e-5)
  assert np.abs(got).max() <= 1.0 and got.std() > 0  # actions in [-1, 1] that depend on the observation
  with open(os.path.join(run_dir, "run.json")) as f:
    cfg = from_dict(json.load(f)["config"])
  env = TrackedRobotEnv(cfg)
  assert [o["name"] for o in meta["observation"]] == observation_names(env)
  meaning = {o["name"]: o["meaning"] for o in meta["observation"]}  # the tiny task observes 2 steps
  assert meaning["v@t-1"] == meaning["v"] + ", 1 control step back" and meaning["v"] == "forward speed (m/s)"
  assert [a["name"] for a in meta["action"]] == list(env.controller.dims)
  assert meta["control"]["period_s"] == cfg.control.period and meta["task"] == "asc-inc-cog"


def test_a_failed_parity_check_writes_nothing(ppo_run, tmp_path, capsys):
  from train import export
  path = tmp_path / "bad.onnx"
  assert export.main([ppo_run[0], "--onnx", str(path), "--tolerance", "-1"]) == 1
  assert not path.exists() and not list(tmp_path.glob("*.tmp"))
  assert "nothing written" in capsys.readouterr().err


def test_onnxruntime_drives_the_simulator_beside_the_jax_policy(ppo_run, tmp_path, capsys):
  """Both loops run the same trials and report; a file that is not there is refused (exit 2). (The
  two agree in distribution, not trial by trial: stair contacts grow 1e-7 action differences.)"""
  from train import export, onnx_drive
  path = str(tmp_path / "p.onnx")
  assert export.main([ppo_run[0], "--onnx", path]) == 0
  assert onnx_drive.main([path, "--trials", "3", "--scene", "uniform", "--compare", ppo_run[0]]) == 0
  lines = capsys.readouterr().out.strip().splitlines()[-2:]
  assert "onnxruntime" in lines[0] and "jax" in lines[1]
  assert onnx_drive.main([str(tmp_path / "none.onnx")]) == 2


def test_the_robustness_suite_runs_every_case_and_low_friction_hurts_full_throttle(tmp_path, capsys):
  """`--robustness` writes a report per case and base scene; full throttle on the hardest staircase
  gets less far on half the friction (mu_along 0.5 < tan 32.2 deg, the incline's) than on the
  nominal robot (the earlier measure: 0.19 vs 1.0). The grid is the test's own three cases."""
  from mjx_tracks.envs.config import load_config
  from train import evaluate
  from train.evaluation import robustness_bases, robustness_scenes
  half = '"randomization.friction_along=[0.5, 0.5]", "randomization.friction_across=[0.5, 0.5]"'
  grid = (f'evaluation.robustness=[{{name: nominal, set: []}}, {{name: half-friction, set: [{half}]}}, '
          '{name: late, set: ["randomization.action_delay=[period, period]"]}]')
  out = tmp_path / "full"
  assert evaluate.main([str(out), "--baseline", "full", "--task", "asc-inc-cog", "--robustness", "--trials", "2",
                        "--set", grid, "--db", str(tmp_path / "db.sqlite")]) == 0
  said, cfg = capsys.readouterr().err, load_config("asc-inc-cog", [grid])
  assert all(f"{base}: done in " in said for base in robustness_bases(cfg))  # each base scene's time
  scenes = robustness_scenes(cfg)
  assert len(scenes) == 2 * 3
  progress = {}
  for scene in scenes:
    with open(out / f"eval-{scene}.json") as f:
      progress[scene] = json.load(f)["metrics"]["progress"]["mean"]
  assert progress["hardest+half-friction"] < progress["hardest+nominal"] - 0.3

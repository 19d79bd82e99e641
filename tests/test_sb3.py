"""`train.run --library sb3`: a tiny Stable-Baselines3 run on the CPU trains, is interrupted (a stop
request as Ctrl-C makes one), resumes with its replay buffer and curriculum, exports a policy that
acts as SB3's own deterministic policy, is evaluated, and shows in the dashboard's API; the export
of each algorithm against SB3's predict; the presets in study specs; PyTorch beside MuJoCo's EGL
renderer without Triton."""

import glob
import json
import os
import signal
import tempfile

import gymnasium as gym
import numpy as np
import pytest

from fastapi.testclient import TestClient

from helpers import TINY

import train.core.no_triton  # noqa: F401  (before any test imports PyTorch: train.core.no_triton says why)
from train.core.policy import load_policy


class _StopAfter:
  """A StopRequest whose request (SIGINT) arrives after `n` reads of `requested`: the callback
  reads it once per step, so training stops after about n steps, as after a Ctrl-C."""

  def __init__(self, n):
    self.n, self.reads = n, 0

  def __call__(self, *a, **k):
    return self

  def __enter__(self):
    return self

  def __exit__(self, *exc):
    return None

  @property
  def requested(self):
    self.reads += 1
    return signal.SIGINT if self.reads > self.n else None

  exit_code = 130


def _args(out, db, *more):
  """The training tests' tiny task (helpers.TINY: 2 physics steps per control step, no beams)."""
  return ["--library", "sb3", "--task", "asc-inc-cog", "--algo", "sac", "--preset", "cpu", "--steps", "250",
          "--hp", "training_metrics_steps=100", *TINY, "--out", str(out), "--db", str(db), *more]


def test_an_sb3_run_trains_stops_resumes_exports_evaluates_and_shows(tmp_path, monkeypatch, capsys):
  import jax
  from stable_baselines3 import SAC

  from train import evaluate, run
  from train.core import interrupts
  from train.db import ExperimentDB
  from train.server.app import create_app
  from train.server.settings import Settings
  out, db_path = tmp_path / "runs" / "a", tmp_path / "runs" / "experiments.sqlite"
  sb3_log_folders = set(glob.glob(os.path.join(tempfile.gettempdir(), "SB3-*")))  # SB3's default logger makes one per learn()
  monkeypatch.setattr(interrupts, "StopRequest", _StopAfter(120))
  assert run.main(_args(out, db_path)) == 130  # stopped: a checkpoint and the policy saved
  (first,) = [int(p.name) for p in (out / "checkpoints").iterdir()]
  assert 120 <= first < 250 and (out / "checkpoints" / str(first) / "replay_buffer.pkl").exists()
  monkeypatch.setattr(interrupts, "StopRequest", _StopAfter(10**9))
  assert run.main(["--resume", str(out), "--db", str(db_path)]) == 0
  model = SAC.load(out / "checkpoints" / "250" / "model.zip", device="cpu")
  model.load_replay_buffer(out / "checkpoints" / "250" / "replay_buffer.pkl")
  # the buffer went on, not afresh: all but the stopping step's transition (SB3 stores a step after
  # its callback, which ended learn())
  assert model.num_timesteps == 250 and model.replay_buffer.size() == 249
  db = ExperimentDB(str(db_path))
  (rec,) = db.runs()
  events = [e["event"] for e in db.events(rec["run_id"])]
  assert rec["status"] == "done" and events[:4] == ["started", "checkpoint", "interrupted", "resumed"]
  assert [r["step"] for r in db.stats(rec["run_id"])][-1] == 250 and list((out / "tb").iterdir())
  obs = np.random.default_rng(0).normal(size=(1000, model.observation_space.shape[0])).astype(np.float32)
  np.testing.assert_allclose(np.asarray(load_policy(str(out / "policy"))(obs)),
                             model.predict(obs, deterministic=True)[0], atol=1e-5)
  assert evaluate.main([str(out), "--trials", "2", "--db", str(db_path)]) == 0
  report = json.loads((out / "eval-hardest.json").read_text())
  assert (report["trials"], report["policy_step"], report["run_id"]) == (2, 250, json.loads((out / "run.json").read_text())["run_id"])
  client = TestClient(create_app(Settings(str(db_path), str(tmp_path / "runs"))), base_url="http://127.0.0.1")
  (shown,) = client.get("/api/runs").json()
  assert shown["run_id"] == rec["run_id"] and shown["status"] == "done" and shown["step"] == 250
  assert "sb3" in client.get("/api/trainers").json()["library_algos"]
  # --checkpoint evaluates an SB3 checkpoint as a killed run's: the newest holds the exported policy
  from train.core.policy import load_checkpoint_params, load_policy_params
  spec, params, step = load_checkpoint_params(str(out))
  exported_spec, exported = load_policy_params(str(out / "policy"))
  assert (step, spec) == (250, exported_spec)
  for a, b in zip(jax.tree_util.tree_leaves(params), jax.tree_util.tree_leaves(exported), strict=True):
    np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
  assert evaluate.main([str(out), "--checkpoint", str(first), "--trials", "2", "--out", str(tmp_path / "ck.json"),
                        "--db", str(db_path)]) == 0
  ck = json.loads((tmp_path / "ck.json").read_text())
  assert (ck["policy_step"], ck["checkpoint"]) == (first, True)
  # a damaged newest checkpoint: evaluating it fails in one line; training further falls back to the
  # one before, in one warning line, and records no step twice
  (out / "checkpoints" / "250" / "model.zip").write_bytes(b"damaged")
  with pytest.raises(ValueError, match="cannot read checkpoint 250"):
    load_checkpoint_params(str(out))
  capsys.readouterr()
  assert run.main(["--resume", str(out), "--db", str(db_path), "--steps", "300"]) == 0
  said = capsys.readouterr()
  assert f"falling back to checkpoint {first:,}" in said.err and f"from its checkpoint at step {first:,}" in said.out
  steps = [r["step"] for r in db.stats(rec["run_id"])]
  assert steps == sorted(set(steps)) and steps[-1] == 300
  assert set(glob.glob(os.path.join(tempfile.gettempdir(), "SB3-*"))) == sb3_log_folders


def test_an_sb3_run_stops_early_at_the_papers_return(tmp_path):
  """A return threshold every report meets (-1000) ends the run at its first report."""
  from train import run
  from train.db import ExperimentDB
  out, db_path = tmp_path / "e", tmp_path / "experiments.sqlite"
  assert run.main(_args(out, db_path, "--early-stop", "return=-1000", "--checkpoint-every", "0")) == 0
  (rec,) = ExperimentDB(str(db_path)).runs()
  assert rec["status"] == "stopped_early" and [int(p.name) for p in (out / "checkpoints").iterdir()] == [100]
  assert run.main(_args(tmp_path / "f", db_path, "--early-stop", "success")) == 2  # sb3 has no probe


class _Spaces(gym.Env):
  """Spaces alone: SB3 builds its networks from them."""
  observation_space = gym.spaces.Box(-np.inf, np.inf, (9,), np.float32)
  action_space = gym.spaces.Box(-1.0, 1.0, (3,), np.float32)

  def reset(self, *, seed=None, options=None):
    return np.zeros(9, np.float32), {}

  def step(self, action):
    return np.zeros(9, np.float32), 0.0, False, False, {}


@pytest.mark.parametrize("algo", ["sac", "td3", "ppo"])
def test_each_algorithms_export_acts_as_sb3s_deterministic_policy(algo):
  """Random networks (PPO's mean moved off zero so that clipping to [-1, 1] matters)."""
  import stable_baselines3 as sb3
  import torch

  from train.core.policy import make_act
  from train.core.sb3_export import network_spec, policy_params
  model = {"sac": sb3.SAC, "td3": sb3.TD3, "ppo": sb3.PPO}[algo]("MlpPolicy", _Spaces(), seed=1, device="cpu",
                                                                   policy_kwargs={"net_arch": [16, 8]})
  if algo == "ppo":
    with torch.no_grad():
      model.policy.action_net.bias += 0.8
  spec = network_spec(algo, 9, 3, (16, 8))
  act = make_act(spec, policy_params(algo, model, spec))
  obs = np.random.default_rng(2).normal(size=(500, 9)).astype(np.float32) * 3
  ours, theirs = np.asarray(act(obs)), model.predict(obs, deterministic=True)[0]
  np.testing.assert_allclose(ours, np.clip(theirs, -1, 1), atol=1e-5)
  assert np.abs(theirs).max() > 0.5  # the policies act: the comparison is not of zeros


def test_study_specs_take_the_library_and_its_presets():
  from mjx_tracks.envs.config import ConfigError
  from train.study.spec import cells, study_from_dict
  group = {"name": "sb3-td3", "algo": "td3", "preset": "paper", "library": "sb3", "steps": [20000], "backend": "cpu"}
  spec = study_from_dict({"name": "s", "tasks": ["asc-inc-cog"], "seeds": [0, 1], "groups": [group], "baselines": []})
  cell = cells(spec)[0]
  assert cell.train_args()[-4:] == ["--library", "sb3", "--early-stop", "none"]
  for bad, key in (({"algo": "td3", "library": "mjx-tracks"}, "unknown algorithm"),
                   ({"early_stop": "success"}, "has no early stop"), ({"hp": ["gamma=2"]}, "gamma")):
    with pytest.raises(ConfigError, match=key):
      study_from_dict({"name": "s", "tasks": ["asc-inc-cog"], "seeds": [0], "groups": [{**group, **bad}]})


CRASH_SCRIPT = """
import mujoco, mjx_tracks
m = mujoco.MjModel.from_xml_string("<mujoco><worldbody><geom type='sphere' size='1'/></worldbody></mujoco>")
renderer = mujoco.Renderer(m, 32, 32)  # an offscreen GL context (EGL where the machine has it)
renderer.update_scene(mujoco.MjData(m))
renderer.render()
import train.core.sb3_env
import torch
torch.optim.Adam([torch.zeros(2, requires_grad=True)])  # PyTorch would import Triton here
try:
  import triton
  print("triton loaded")
except ImportError:
  print("triton hidden")
"""


def test_pytorch_builds_an_optimizer_beside_an_egl_context_without_loading_triton():
  """Where Triton is installed, loading it after an EGL context crashed the process (segmentation
  fault: a lost pytest worker, then a hung session); train.core.no_triton hides it from PyTorch."""
  import subprocess
  import sys
  out = subprocess.run([sys.executable, "-c", CRASH_SCRIPT], capture_output=True, text=True, timeout=300,
                       env={**os.environ, "JAX_PLATFORMS": "cpu"})
  assert out.returncode == 0, (out.returncode, out.stderr[-2000:])
  assert out.stdout.strip().endswith("triton hidden"), out.stdout

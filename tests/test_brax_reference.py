"""The environment stays a Brax Env: Brax's own ppo.train trains it (`train.run --library brax`,
train.core.brax_reference), recorded like any run."""

import json
import os
import sqlite3

import numpy as np

from helpers import TRAIN_TINY
from train import run


def test_brax_ppo_train_trains_the_env_and_is_recorded_like_any_run(tmp_path, capsys):
  from train.core.policy import load_policy
  out, db = str(tmp_path / "brax"), str(tmp_path / "db.sqlite")
  assert run.main([*TRAIN_TINY, "--library", "brax", "--steps", "512", "--out", out, "--db", db]) == 0
  info = json.load(open(os.path.join(out, "policy", "policy.json")))
  meta = json.load(open(os.path.join(out, "run.json")))
  assert info["trainer"] == "brax" and info["algo"] == "ppo" and meta["library"] == "brax"
  with sqlite3.connect(db) as c:
    assert c.execute("SELECT status, run_id FROM experiments").fetchall() == [("done", meta["run_id"])]
  act = load_policy(os.path.join(out, "policy"))
  a = np.asarray(act(np.zeros((3, 12), np.float32)))  # the tiny task: 6 entries x 2 steps
  assert a.shape == (3, 5) and np.all(np.abs(a) <= 1)
  said = capsys.readouterr().out
  assert "done: 512 steps in " in said and "last training episodes" not in said  # none to report
  assert run.main(["--resume", out]) == 2  # Brax saves no checkpoints
  assert "was trained by --library brax, which saves no checkpoints" in capsys.readouterr().err


def test_brax_wraps_its_evaluation_env_with_the_evaluation_scenes():
  """Brax applies one wrap_env_fn to the training and the evaluation env: each must keep its own
  scene sampler (the evaluation's uniform scenes, not the training curriculum's)."""
  from mjx_tracks.envs.config import load_config
  from mjx_tracks.envs.task_env import TrackedRobotEnv
  from mjx_tracks.envs.wrappers import wrap_for_training
  from train.evaluation import scene_config
  cfg = load_config("asc-inc-cog", ())
  train_core, eval_core = TrackedRobotEnv(cfg), TrackedRobotEnv(scene_config(cfg, "uniform"))
  wrap = wrap_for_training("i")
  assert wrap(train_core, 10, 1).core is train_core
  assert wrap(eval_core, 10, 1).core is eval_core

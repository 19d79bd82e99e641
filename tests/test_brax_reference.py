"""The environment stays a Brax Env: Brax's own ppo.train trains it (train.brax_reference)."""

import json
import os

import numpy as np

from helpers import TRAIN_TINY
from train import brax_reference


def test_brax_ppo_train_trains_the_env_and_exports_an_evaluable_policy(tmp_path):
  from train.policy import load_policy
  out = str(tmp_path / "brax")
  assert brax_reference.main([*TRAIN_TINY, "--steps", "512", "--out", out]) == 0
  info = json.load(open(os.path.join(out, "policy", "policy.json")))
  assert info["trainer"] == "brax" and info["algo"] == "ppo"
  act = load_policy(os.path.join(out, "policy"))
  a = np.asarray(act(np.zeros((3, 6), np.float32)))
  assert a.shape == (3, 5) and np.all(np.abs(a) <= 1)


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

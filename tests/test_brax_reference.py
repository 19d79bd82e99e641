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

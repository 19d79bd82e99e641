"""SAC end to end on the CPU (its own file, so that pytest-xdist can run it beside the PPO tests)."""

import os

import numpy as np

from helpers import TINY, run_id
from train import db as dbmod
from train import run


def test_sac_tiny_run_trains_and_exports(tmp_path):
  from train.policy import load_policy
  out = str(tmp_path / "sac")
  rc = run.main(["--task", "des-inc-ang", "--algo", "sac", "--preset", "cpu", "--steps", "256",
                 "--out", out, "--db", str(tmp_path / "db.sqlite"), *TINY])
  assert rc == 0
  act = load_policy(os.path.join(out, "policy"))
  assert np.asarray(act(np.zeros((2, 6), np.float32))).shape == (2, 5)
  assert dbmod.ExperimentDB(str(tmp_path / "db.sqlite")).run(run_id(out))["status"] == "done"

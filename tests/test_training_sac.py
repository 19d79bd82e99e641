"""SAC end to end on the CPU (its own file, so that pytest-xdist can run it beside the PPO tests)."""

import os

import numpy as np

from helpers import TINY, run_id
from train import db as dbmod
from train import run
from train.core.checkpoints import RunCheckpoints

SAC_TINY = ["--task", "des-inc-ang", "--algo", "sac", "--preset", "cpu", *TINY]


def test_sac_trains_exports_and_resumes_bit_for_bit_with_its_replay_buffer(tmp_path):
  from train.core.policy import load_policy
  whole, part = str(tmp_path / "whole"), str(tmp_path / "part")
  database = str(tmp_path / "db.sqlite")
  assert run.main([*SAC_TINY, "--steps", "256", "--out", whole, "--db", database]) == 0
  act = load_policy(os.path.join(whole, "policy"))
  assert np.asarray(act(np.zeros((2, 6), np.float32))).shape == (2, 5)
  assert dbmod.ExperimentDB(database).run(run_id(whole))["status"] == "done"
  # the same run in two sessions: 128 steps (the buffer is past min_replay_size), then resumed to 256
  assert run.main([*SAC_TINY, "--steps", "128", "--out", part, "--db", database]) == 0
  assert run.main(["--resume", part, "--steps", "256", "--db", database]) == 0
  a, b = RunCheckpoints(whole).arrays(256), RunCheckpoints(part).arrays(256)
  _, meta = RunCheckpoints(whole).restore(256)
  assert any(".buffer.data" in leaf["path"] for leaf in meta["layout"])
  for k in a:
    np.testing.assert_array_equal(b[k], a[k], err_msg=k)

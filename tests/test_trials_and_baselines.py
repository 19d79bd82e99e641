"""Evaluation trials are samples: the start jitter against its uniform distribution, and a baseline
evaluated by `train.evaluate --baseline` like a trained run (run record, report, database), whose
trials on one scene differ."""

import json
import os

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import TINY_SETTINGS

import mjx_tracks
from mjx_tracks.envs.config import ConfigError
from train import evaluate
from train.db import ExperimentDB

N = 512  # resets drawn: the standard error of a U(-a, a) variance estimate is about a^2 / 15 at this size
JITTER = (0.1, 0.2, 0.3)  # m, rad, rad


def _starts(jitter, settings=(), n=N):
  core = mjx_tracks.load("asc-inc-cog", [*TINY_SETTINGS, f"scene.start_jitter={list(jitter)}", *settings])
  keys = jax.random.split(jax.random.PRNGKey(3), n)
  s = jax.jit(jax.vmap(core.reset_at, in_axes=(0, None, None)))(keys, jnp.float32(0.5), jnp.float32(1.0))
  es = s.pipeline_state
  qpos = np.asarray(es.data.qpos)
  yaw = 2 * np.arctan2(qpos[:, 6], qpos[:, 3])  # a yaw-only quaternion (w, 0, 0, z)
  return core, es, qpos, yaw


def test_the_start_jitter_is_uniform_within_its_bounds_and_the_servos_start_where_the_joints_are():
  core, es, qpos, yaw = _starts(JITTER)
  _, es0, qpos0, yaw0 = _starts((0.0, 0.0, 0.0))
  spawn = np.asarray(es.scene.spawn_pos)
  np.testing.assert_allclose(np.asarray(es0.scene.spawn_pos)[:, :2], qpos0[:, :2], atol=1e-6)  # none: the spawn
  np.testing.assert_allclose(np.asarray(es0.targets), 0.0)
  joints = qpos[:, np.asarray(core.sim.layout.joint_qpos)]
  limits = np.asarray(core.controller.joint_limits)
  for a, x in ((JITTER[0], qpos[:, 0] - spawn[:, 0]), (JITTER[0], qpos[:, 1] - spawn[:, 1]),
               (JITTER[1], (yaw - yaw0 + np.pi) % (2 * np.pi) - np.pi), (JITTER[2], joints[:, 0])):
    assert np.abs(x).max() <= a + 1e-6
    assert abs(x.mean()) < 4 * a / np.sqrt(3 * N)  # U(-a, a): mean 0, sd a / sqrt(3)
    assert x.var() == pytest.approx(a * a / 3, rel=0.2)
  assert (joints >= limits[:, 0] - 1e-6).all() and (joints <= limits[:, 1] + 1e-6).all()
  np.testing.assert_allclose(np.asarray(es.targets), joints, atol=1e-6)


def test_the_start_pose_places_its_joint_groups_within_their_limits_and_the_others_at_0():
  core, es, qpos, _ = _starts((0.0, 0.0, 0.0), ["control.start_pose=[[front, 2.0], [arm_1, -0.3]]"], n=4)
  joints = qpos[:, np.asarray(core.sim.layout.joint_qpos)]
  names = core.robot.joint_names()  # front flippers clipped to their limit (pi / 4), arm_1 at -0.3, the rest 0
  expected = [np.pi / 4 if n.startswith("flipper_front") else -0.3 if n == "arm_1" else 0.0 for n in names]
  np.testing.assert_allclose(joints, np.broadcast_to(expected, joints.shape), atol=1e-6)
  np.testing.assert_allclose(np.asarray(es.targets), joints, atol=1e-6)
  with pytest.raises(ConfigError, match="not a joint group"):
    mjx_tracks.load("asc-inc-cog", ["control.start_pose=[[nose, 0.5]]"])


def test_a_baseline_is_evaluated_and_recorded_like_a_run_and_its_trials_are_samples(tmp_path, capsys):
  out, db = str(tmp_path / "zero"), str(tmp_path / "db.sqlite")
  args = ["--baseline", "scripted", "--task", "asc-inc-cog", *[a for s in TINY_SETTINGS for a in ("--set", s)],
          "--scene", "hardest", "--trials", "8", "--db", db, out]
  assert evaluate.main(args) == 0
  meta = json.load(open(os.path.join(out, "run.json")))
  assert (meta["algo"], meta["preset"], meta["task"]) == ("baseline", "scripted", "asc-inc-cog")
  report = json.load(open(os.path.join(out, "eval-hardest.json")))
  assert report["trials"] == 8 and report["policy_step"] is None
  assert len(set(report["per_trial"]["final_x"])) == 8  # varied starts: eight different trials, not one repeated
  rows = ExperimentDB(db).evals(meta["run_id"])
  assert len(rows) == 8 and ExperimentDB(db).run(meta["run_id"])["algo"] == "baseline"
  assert evaluate.main(args) == 0  # again: the same folder and run
  assert json.load(open(os.path.join(out, "run.json")))["run_id"] == meta["run_id"]
  capsys.readouterr()
  assert evaluate.main([*args[:-1], "--set", "episode.max_steps=9", out]) == 2  # the folder's settings differ
  assert "other settings" in capsys.readouterr().err
  assert evaluate.main(["--baseline", "scripted", "--task", "nav", "--db", db, str(tmp_path / "n")]) == 2
  assert "cannot drive nav" in capsys.readouterr().err
  assert evaluate.main(["--baseline", "zero", "--task", "asc-inc-cog", "--db", db, out]) == 2  # another baseline's folder
  assert "not baseline zero" in capsys.readouterr().err
  assert evaluate.main(["--task", "asc-inc-cog", out]) == 2 and "--baseline NAME" in capsys.readouterr().err


def test_live_steps_end_at_each_trials_first_done_and_run_to_the_end_without_one():
  from train.evaluation import live_steps
  # 4 steps, 3 trials (float flags as a rollout gives them): 0 ends at step 1 (and is flagged again
  # at step 3), 1 never ends, 2 ends at step 0
  done = np.array([[0, 0, 1], [1, 0, 0], [0, 0, 1], [1, 0, 0]], np.float32)
  assert live_steps(done).astype(int).tolist() == [[1, 1, 1], [1, 1, 0], [0, 1, 0], [0, 1, 0]]

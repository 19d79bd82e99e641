"""train.eval_ahead (`train.evaluate --await-runs`): the waiting ends when stdin speaks, read
through a real pipe; a run's latest checkpoint stands in for its policy with the same network and
the same shapes (what the programs compiled ahead are later called with). The compilation ahead
itself: tests/test_task_pack.py and tests/test_training.py."""

import io
import os
import shutil
import threading

import jax
import numpy as np

from train import eval_ahead


def test_the_wait_for_checkpoints_ends_when_stdin_is_written_to_or_closed(tmp_path, monkeypatch):
  monkeypatch.setattr(eval_ahead, "POLL_S", 0.02)
  folder = str(tmp_path / "no-run-yet")  # never gets a record nor a checkpoint
  r, w = os.pipe()
  writer = os.fdopen(w, "w")
  with os.fdopen(r) as stdin:
    assert eval_ahead._readable(stdin) is False
    timer = threading.Timer(0.2, lambda: (writer.write(folder + "\n"), writer.close()))
    timer.start()
    assert eval_ahead._wait_for_checkpoints([folder], stdin) is False  # it returned once written to
    timer.join()
    assert eval_ahead._readable(stdin) is True
    assert eval_ahead.named_runs(stdin, [str(tmp_path / "other"), folder]) == [folder]
  r, w = os.pipe()
  os.close(w)  # closed without a word: the training ended no run
  with os.fdopen(r) as stdin:
    assert eval_ahead._wait_for_checkpoints([folder], stdin) is False and eval_ahead.named_runs(stdin, [folder]) == []
  assert eval_ahead._readable(io.StringIO("")) is None  # no descriptor: the compilation is not held back


def test_a_runs_latest_checkpoint_stands_in_for_its_policy(ppo_run, tmp_path):
  out, _ = ppo_run
  during = str(tmp_path / "during")  # as the run is while it trains: checkpoints, no exported policy
  shutil.copytree(out, during, ignore=shutil.ignore_patterns("policy", "milestones"))
  assert eval_ahead._has_parameters(during) and not eval_ahead._has_parameters(str(tmp_path / "nothing"))
  (spec, params), (spec_then, params_then) = eval_ahead._latest_params(during), eval_ahead._latest_params(out)
  assert spec == spec_then
  shapes = [jax.tree_util.tree_map(lambda x: (np.shape(x), np.asarray(x).dtype), p) for p in (params, params_then)]
  assert jax.tree_util.tree_structure(params) == jax.tree_util.tree_structure(params_then) and shapes[0] == shapes[1]

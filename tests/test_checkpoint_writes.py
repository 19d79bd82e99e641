"""How a run's checkpoints are written (train.core.checkpoints, train.core.loop.Checkpointer): the
state's leaves as one array of bytes, read back exactly (every dtype, empty and 0-d leaves), as are
checkpoints written before as one array per leaf; a layout that does not fit is refused; timed
checkpoints written in the background while training goes on, the database recording a step only
once it is complete on disk; the runs of a program that end together start their writes at once; a
write that fails after the training failed is reported, not raised over that failure; a run's
slice of the program's states on the host stays there."""

import collections
import time
import types

import jax
import numpy as np
import orbax.checkpoint as ocp
import pytest

from mjx_tracks.envs.wrappers import global_stats_from_json
from train.core.checkpoints import PACKED, CheckpointError, RunCheckpoints, flatten_state, saved_steps, unflatten_state
from train.core.group_loop import GroupLoop, Member, run_slice
from train.core.loop import Checkpointer, Schedule, settle_all

State = collections.namedtuple("State", "env_state params")
EnvState = collections.namedtuple("EnvState", "info")
GLOBAL = {"curriculum": {"eps": 0.25, "returns": [0.0, 1.0], "progress": [0.5, 0.5], "head": 1, "finished": 2,
                         "updates": 3}, "normalizer": {"k": 1.0, "total": 2.0, "count": 4}}


def _state(value: float) -> State:
  """A host training state as the loop checkpoints it: the env batch's global statistics (a
  leading axis of 1) and some parameters."""
  batched = jax.tree_util.tree_map(lambda x: np.asarray(x)[None], global_stats_from_json(GLOBAL))
  return State(EnvState({"global": batched}), {"w": np.full((3, 4), value, np.float32)})


LEARNER = types.SimpleNamespace(policy_params=lambda s: (s.params, s.params))


def test_a_timed_checkpoint_is_recorded_only_once_it_is_whole_on_disk_and_reads_back(tmp_path):
  recorded = []
  ckpts = RunCheckpoints(str(tmp_path))
  c = Checkpointer(ckpts, {"algo": "x"}, LEARNER, lambda step: recorded.append((step, saved_steps(str(tmp_path)))),
                   every_s=60.0)
  c.save(_state(1.0), 100, wait=False)
  assert recorded == [] and c.unsettled == 100  # in flight: not in the database yet
  c.save(_state(2.0), 200, wait=False)  # the next save waits for the one before, then records it
  assert recorded == [(100, [100])] and c.unsettled == 200
  deadline = time.monotonic() + 60
  while c.unsettled is not None and time.monotonic() < deadline:  # the loop asks after each update
    c.poll()
    time.sleep(0.01)
  assert recorded == [(100, [100]), (200, [100, 200])]  # recorded once written, without a wait
  recorded.clear()
  c.save(_state(2.0), 200)  # the same step again (a run's finish after a round): no second write
  assert recorded == [] and c.unsettled is None
  c.save(_state(3.0), 300, wait=False)
  c.save(_state(3.0), 300)  # a finish right after a round: waits for its write
  assert recorded == [(300, [100, 200, 300])] and c.unsettled is None
  state, meta = ckpts.restore_state(300, _state(0.0))
  assert meta["step"] == 300 and meta["global"]["curriculum"]["head"] == 1
  np.testing.assert_array_equal(state.params["w"], np.full((3, 4), 3.0, np.float32))


def test_runs_ending_together_start_their_writes_before_any_run_is_finished():
  """Three runs end at the program's last step: each one's checkpoint is started (in the
  background) before the first run's finish, which waits for its own."""
  log = []

  class Logged(Checkpointer):
    def save(self, state, step, wait=True):
      log.append(("save", int(state), step, wait))

  members = [Member(Logged(None, {}, None, lambda step: None, every_s=1e9), lambda step, m: {}, Schedule(100),
                    lambda r, i=i: log.append(("finish", i, r.step))) for i in range(3)]
  GroupLoop(lambda s: (s + 1, {}), 100, members, types.SimpleNamespace(requested=None)).run(np.zeros(3), 0, 200)
  assert log == [("save", 2, 200, False)] * 3 + [("finish", i, 200) for i in range(3)]


def test_a_write_that_fails_while_a_failure_is_handled_is_reported_in_one_line(capsys):
  class Broken:
    def wait(self):
      raise OSError("disk full")
  recorded = []
  c = Checkpointer(Broken(), {}, None, recorded.append, every_s=60.0, unsettled=300)
  settle_all([c, Checkpointer(None, {}, None, recorded.append, every_s=60.0)])
  err = capsys.readouterr().err
  assert recorded == [] and err.count("\n") == 1 and "checkpoint being written failed (OSError: disk full)" in err


MIXED = {"f": np.arange(6, dtype=np.float32).reshape(2, 3) / 7, "i": np.array([-3, 5], np.int32),
         "b": np.array([True, False, True]), "u": np.array([[1, 2**32 - 1]], np.uint32), "scalar": np.float32(0.25),
         "empty": np.zeros((0, 4), np.float32), "d": np.array([1e-300], np.float64), "h": np.array([1.5], np.float16)}


def test_the_states_leaves_are_one_array_of_bytes_that_reads_back_exactly_and_a_layout_that_does_not_fit_is_refused():
  arrays, layout = flatten_state(MIXED)
  assert list(arrays) == [PACKED] and arrays[PACKED].dtype == np.uint8
  assert arrays[PACKED].size == sum(np.asarray(x).nbytes for x in MIXED.values())
  back = unflatten_state(arrays, layout, jax.tree_util.tree_map(np.asarray, MIXED))
  for name, want in MIXED.items():
    got = back[name]
    assert got.dtype == np.asarray(want).dtype and got.shape == np.shape(want) and np.array_equal(got, want), name
  with pytest.raises(CheckpointError, match="holds 4 bytes, its layout"):
    unflatten_state({PACKED: np.zeros(4, np.uint8)}, layout, MIXED)


def test_a_checkpoint_written_as_one_array_per_leaf_reads_back(tmp_path):
  """Checkpoints before 2026-11-29: the state item holds leaf_NNNNN arrays (none for an empty leaf)."""
  _, layout = flatten_state(MIXED)
  leaves = jax.tree_util.tree_leaves(MIXED)
  old = {f"leaf_{i:05d}": np.asarray(x) for i, x in enumerate(leaves) if np.size(x)}
  ckpts = RunCheckpoints(str(tmp_path))
  ckpts.mgr.save(7, args=ocp.args.Composite(state=ocp.args.StandardSave(old), params=ocp.args.StandardSave({"w": np.ones(2)}),
                                            meta=ocp.args.JsonSave({"step": 7, "layout": layout})))
  ckpts.wait()
  state, meta = ckpts.restore_state(7, jax.tree_util.tree_map(np.asarray, MIXED))
  assert meta["step"] == 7 and all(np.array_equal(state[k], v) for k, v in MIXED.items())
  assert sorted(ckpts.arrays(7)) == sorted(old)


def test_a_run_of_a_host_tree_is_sliced_on_the_host_though_brax_keeps_its_count_on_the_device():
  """to_host's trees hold Brax's UInt64 normalizer count as jax arrays (its __post_init__ makes them
  so): a run's slice of such a tree is numpy views of the host arrays, not the whole tree sent to
  the device and each run's slice fetched back."""
  from brax.training.types import UInt64
  host = {"buffer": np.arange(3 * 1000, dtype=np.float32).reshape(3, 1000),
          "count": UInt64(hi=np.zeros(3, np.uint32), lo=np.array([5, 6, 7], np.uint32))}
  assert isinstance(host["count"].lo, jax.Array)  # what makes the tree not all numpy
  one = run_slice(host, 1)
  assert isinstance(one["buffer"], np.ndarray) and np.shares_memory(one["buffer"], host["buffer"])
  assert int(one["count"].lo) == 6 and one["buffer"][0] == 1000.0


def test_a_checkpoint_whose_bytes_disagree_with_its_layout_is_skipped_for_the_one_before(tmp_path):
  """Damage, not another run's checkpoint: a resume reports it in one line and takes the older one."""
  ckpts, said = RunCheckpoints(str(tmp_path)), []
  for step, value in ((1, 1.0), (2, 2.0)):
    ckpts.save(step, _state(value), ({"w": np.ones(2)},), {"algo": "x"})
  arrays, layout = flatten_state(_state(3.0))
  ckpts.mgr.save(3, args=ocp.args.Composite(state=ocp.args.StandardSave({PACKED: arrays[PACKED][:-4]}),
                                            params=ocp.args.StandardSave({"w": np.ones(2)}),
                                            meta=ocp.args.JsonSave({"step": 3, "layout": layout})))
  ckpts.wait()
  state, meta = ckpts.restore_latest_good(_state(0.0), say=said.append)
  assert meta["step"] == 2 and np.array_equal(state.params["w"], np.full((3, 4), 2.0, np.float32))
  assert len(said) == 1 and "checkpoint 3 " in said[0] and "falling back to checkpoint 2" in said[0]

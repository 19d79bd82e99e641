"""Timed checkpoints written in the background (train.core.loop.Checkpointer, train.core.checkpoints):
training goes on while orbax writes; the database records a step only once it is complete on disk;
the runs of a program that end together start their writes at once; a write that fails after the
training failed is reported, not raised over that failure."""

import collections
import types

import jax
import numpy as np

from mjx_tracks.envs.wrappers import global_stats_from_json
from train.core.checkpoints import RunCheckpoints, saved_steps
from train.core.group_loop import GroupLoop, Member
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
  c.save(_state(2.0), 200)  # the same step again (a run's finish after a round): no second write, only the wait
  assert recorded == [(100, [100]), (200, [100, 200])] and c.unsettled is None
  state, meta = ckpts.restore_state(200, _state(0.0))
  assert meta["step"] == 200 and meta["global"]["curriculum"]["head"] == 1
  np.testing.assert_array_equal(state.params["w"], np.full((3, 4), 2.0, np.float32))


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

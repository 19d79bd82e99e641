"""PPO's update as programs compiled side by side (train.core.algos.ppo_split) against the one
program it stands for (PPO.update), from the same state: the tiny PPO run of conftest's ppo_run,
whose fused update the persistent cache holds."""

import gc
import io

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import HELD_OUT_SET, TINY

from train.core.algos import ppo_split
from train.core.build import build, compile_update, init_state
from train.core.plan import plan_run
from train.run import parser


@pytest.fixture(scope="module")
def updates(tmp_path_factory):
  """(training, fused update, split update, what compiling the split one printed)."""
  args = ["--task", "asc-inc-cog", "--preset", "cpu", "--out", str(tmp_path_factory.mktemp("split") / "run"), *TINY,
          "--set", HELD_OUT_SET]
  t = build(plan_run(parser().parse_args(args)))
  said = io.StringIO()
  fused, _ = compile_update(t, stream=io.StringIO())
  split, _ = compile_update(t, stream=said, split=True)
  return t, fused, split, said.getvalue()


def _copy(state):
  return jax.tree_util.tree_map(jnp.copy, state)  # the updates donate their state


def _worst(a, b) -> float:
  """The largest difference between two trees' leaves, relative to the first's largest magnitude;
  inf where an integer or boolean leaf differs."""
  worst = 0.0
  for x, y in zip(jax.tree_util.tree_leaves(a), jax.tree_util.tree_leaves(b), strict=True):
    x, y = np.asarray(x), np.asarray(y)
    assert x.shape == y.shape and x.dtype == y.dtype
    if not np.issubdtype(x.dtype, np.floating):
      worst = max(worst, 0.0 if np.array_equal(x, y) else np.inf)
      continue
    scale = float(np.max(np.abs(x))) if x.size else 0.0
    worst = max(worst, float(np.max(np.abs(x - y))) / max(scale, 1e-6) if x.size else 0.0)
  return worst


def test_the_split_update_computes_the_fused_one(updates):
  t, fused, split, _ = updates
  start = init_state(t, 0)
  one, two = fused(_copy(start)), split(_copy(start))  # (state, metrics) each
  # the same keys, actions, episodes and SGD: equal to float32 rounding (XLA fuses the programs
  # differently; 6e-6 seen, 2026-11-29) ...
  assert _worst(one, two) < 1e-4
  assert set(one[1]) == set(two[1])
  # ... and the tolerance tells updates apart: from another key the split update lands far from it
  other = split(_copy(start).replace(key=jax.random.PRNGKey(7)))
  assert _worst(one, other) > 1e-2
  # a second update from the first's state: the keys of the next update carried over alike
  assert _worst(fused(one[0]), split(two[0])) < 1e-3


def test_the_split_update_reports_its_programs(updates):
  t, _, _, said = updates
  line = next(line for line in said.splitlines() if "its programs" in line)
  assert [part.split()[0] for part in line.split(": ", 1)[1].split(", ")] == list(ppo_split.PROGRAMS)
  assert gc.get_freeze_count() > 0  # the objects left by compiling, out of the collector's full passes


def test_which_runs_split_their_update():
  assert ppo_split.wanted("on", "ppo")
  assert not ppo_split.wanted("off", "ppo")
  assert not ppo_split.wanted("on", "sac")  # SAC's update stays one program
  assert not ppo_split.wanted("on", "ppo", devices=2)  # nor one on several devices
  assert ppo_split.wanted("auto", "ppo") == (jax.default_backend() != "cpu")
  with pytest.raises(ValueError, match="--split-update takes one of"):
    ppo_split.wanted("yes", "ppo")

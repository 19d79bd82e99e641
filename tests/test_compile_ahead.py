"""The in-training probes' programs compiled ahead, in threads beside the training step's
(train.core.ahead, `train.run --compile-ahead`): the first probe after it compiles nothing large
and reports what it reports without it. (Brax's evaluations: tests/test_evaluator.py, beside the
same evaluations as they come. The runs of tests/conftest.py's ppo_run and tests/test_group.py's
program train with it on.)"""

import jax
import pytest

from helpers import Compilations, pack_plans, seeds_states
from train import evaluation
from train.core import ahead
from train.core.build import build
from train.core.group_loop import run_slice
from train.core.probe import GroupProbe, Probe


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
  """(t, states): helpers.PACK's first run (tiny SAC) and two runs' fresh states of its task, seeds
  helpers.SEEDS (a `train.run --seeds` program)."""
  t = build(pack_plans(tmp_path_factory.mktemp("ahead"))[0])
  return t, seeds_states(t)


def _first_use_compiles_nothing_large_and_reports_the_same(make, use, example):
  """use(make()) twice: once as it comes, once after compile_ahead(example) (a fresh object each
  time, so the first compiles its programs itself or loads them from the persistent cache): the
  same report, and the second's first use neither compiles nor loads a large program."""
  with Compilations() as cold:
    want = use(make())
  computation = make()
  computation.compile_ahead(example)
  with Compilations() as warm:
    got = use(computation)
  assert cold.large() >= 1 and warm.large() == 0, (cold.seconds, cold.cache_hits, warm.seconds, warm.cache_hits)
  return want, got


def test_the_probe_and_a_programs_probe_compiled_ahead(tiny):
  """The run's probe has 3 trials: it is then the program of tests/test_task_pack.py's evaluation of
  a run of this task (3 trials), compiled once in the suite and loaded from the cache the other time."""
  t, states = tiny
  one = run_slice(states, 0)
  want, got = _first_use_compiles_nothing_large_and_reports_the_same(lambda: Probe(t, trials=3), lambda p: p(one), one)
  assert want == got and 0.0 <= want["probe/progress_mean"] <= 1.0

  def probe(group):
    group.at(states, 0)
    return group.result(1)
  want, got = _first_use_compiles_nothing_large_and_reports_the_same(lambda: GroupProbe(t, trials=4), probe, states)
  assert want == got
  with pytest.MonkeyPatch.context() as mp:  # the runs' trials vmapped in one program, as on a GPU
    mp.setattr(evaluation, "vmapped_trials", lambda: True)
    want, got = _first_use_compiles_nothing_large_and_reports_the_same(lambda: GroupProbe(t, trials=4), probe, states)
  assert want == got


def test_compile_ahead_is_on_where_the_backend_is_not_the_cpu_unless_asked():
  assert not ahead.wanted("off") and ahead.wanted("on")
  assert ahead.wanted("auto") == (jax.default_backend() != "cpu")
  with pytest.raises(ValueError, match="--compile-ahead takes one of auto, on, off"):
    ahead.wanted("yes")

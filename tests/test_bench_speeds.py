"""`python -m train.bench speeds`: its constant actions are the baselines' at the ends of the speed
range (mjx_tracks.baselines: full = 1 m/s, zero = half speed), and bad inputs fail in one line."""

import types

import jax.numpy as jnp
import numpy as np
import pytest

import mjx_tracks
from mjx_tracks.baselines import baseline
from train.bench import __main__ as bench
from train.bench.result import BenchInputError
from train.bench.speeds import constant_action


def test_constant_actions_match_the_baselines_and_raise_the_named_joint_dimension():
  core = mjx_tracks.load("asc-inc-cog")
  states = types.SimpleNamespace(obs=jnp.zeros((3, core.observation_size)))
  lo, hi = core.cfg.control.v_range
  for name, speed in (("full", hi), ("zero", (lo + hi) / 2)):
    np.testing.assert_allclose(np.broadcast_to(constant_action(core.cfg, core, speed, ""), (3, core.action_size)),
                               baseline(name).make(core)(states), atol=1e-6)
  raised = np.asarray(constant_action(core.cfg, core, hi, "front"))
  assert raised[core.controller.dims.index("front")] == 1.0 and raised.sum() == 2.0
  with pytest.raises(BenchInputError, match="outside the task's v_range"):
    constant_action(core.cfg, core, hi + 0.5, "")
  with pytest.raises(BenchInputError, match="not an action dimension"):
    constant_action(core.cfg, core, hi, "nose")


def test_a_speed_that_is_not_a_number_fails_before_anything_compiles(capsys):
  assert bench.main(["speeds", "--speeds", "0.5,fast", "--out", "/nonexistent/x.json"]) == 2
  assert "--speeds: numbers in m/s" in capsys.readouterr().err

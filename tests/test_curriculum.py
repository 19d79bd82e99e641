"""Curriculum state: eps follows the rule over finished episodes only; jit == eager; devices agree."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from scenes.curriculum import Curriculum


def _stream(seed=0, steps=60, batch=8):
  rng = np.random.default_rng(seed)
  done = rng.random((steps, batch)) < 0.3
  returns = rng.normal(0.4, 0.5, (steps, batch)).astype(np.float32)
  progress = rng.random((steps, batch)).astype(np.float32)
  return done, returns, progress


def _reference_eps(done, values, window):
  """Plain-Python rule: mean of the last `window` finished values (batch order), the window's
  missing episodes counted as 0, clipped."""
  finished = [v for d_row, v_row in zip(done, values) for d, v in zip(d_row, v_row) if d]
  return float(np.clip(sum(finished[-window:]) / window, 0, 1)) if finished else 0.0


@pytest.mark.parametrize("rule", ["return", "progress"])
@pytest.mark.parametrize("window", [5, 20])
def test_eps_follows_the_rule_over_finished_episodes(rule, window):
  cur = Curriculum(window=window, rule=rule)
  done, returns, progress = _stream()
  values = returns if rule == "return" else progress
  s = cur.init()
  update = jax.jit(cur.update)
  for t in range(len(done)):
    s = update(s, jnp.asarray(done[t]), jnp.asarray(returns[t]), jnp.asarray(progress[t]))
    assert float(s.eps) == pytest.approx(_reference_eps(done[: t + 1], values[: t + 1], window), abs=1e-5)
  assert int(s.finished) == done.sum()


def test_unfinished_episodes_are_never_counted():
  cur = Curriculum(window=4, rule="return")
  s = cur.init()
  done = jnp.array([False, True, False, False])
  s = cur.update(s, done, jnp.array([100.0, 0.3, -50.0, 7.0]), jnp.zeros(4))
  assert float(s.eps) == pytest.approx(0.3 / 4)  # one of four window slots filled
  s = cur.update(s, jnp.zeros(4, bool), jnp.full(4, 9.0), jnp.zeros(4))
  assert float(s.eps) == pytest.approx(0.3 / 4) and int(s.finished) == 1


def test_one_lucky_first_episode_moves_eps_by_one_over_the_window():
  cur = Curriculum(window=20, rule="progress")
  s = cur.update(cur.init(), jnp.array([True]), jnp.ones(1), jnp.ones(1))
  assert float(s.eps) == pytest.approx(1 / 20)


def test_more_finished_than_window_keeps_the_last_ones():
  cur = Curriculum(window=3, rule="progress")
  s = cur.update(cur.init(), jnp.ones(6, bool), jnp.zeros(6), jnp.array([0.0, 0, 0, 0.3, 0.6, 0.9]))
  assert float(s.eps) == pytest.approx(0.6)


def test_jitted_and_eager_updates_agree():
  cur = Curriculum(window=7, rule="progress")
  done, returns, progress = _stream(seed=3)
  s_jit, s_eager = cur.init(), cur.init()
  for t in range(len(done)):
    args = (jnp.asarray(done[t]), jnp.asarray(returns[t]), jnp.asarray(progress[t]))
    s_jit = jax.jit(cur.update)(s_jit, *args)
    s_eager = cur.update(s_eager, *args)
  for a, b in zip(jax.tree_util.tree_leaves(s_jit), jax.tree_util.tree_leaves(s_eager)):
    np.testing.assert_allclose(np.asarray(a), np.asarray(b), rtol=1e-6)  # XLA may fuse the division


def test_split_across_devices_equals_one_device():
  """Two 'devices' (a named vmap axis) each holding half the batch reach the single-device state."""
  cur = Curriculum(window=6, rule="return")
  done, returns, progress = _stream(seed=5, batch=8)
  single = cur.init()
  multi = jax.tree_util.tree_map(lambda x: jnp.stack([x, x]), cur.init())
  step = jax.jit(jax.vmap(lambda s, d, r, p: cur.update(s, d, r, p, axis_name="dev"), axis_name="dev"))
  for t in range(len(done)):
    single = cur.update(single, jnp.asarray(done[t]), jnp.asarray(returns[t]), jnp.asarray(progress[t]))
    split = lambda x: jnp.asarray(x[t]).reshape(2, 4)
    multi = step(multi, split(done), split(returns), split(progress))
  np.testing.assert_allclose(np.asarray(multi.eps), float(single.eps), atol=1e-6)
  np.testing.assert_array_equal(np.asarray(multi.returns[0]), np.asarray(single.returns))


def test_bad_settings_fail_clearly():
  with pytest.raises(ValueError, match="rule"):
    Curriculum(window=20, rule="median")
  with pytest.raises(ValueError, match="window"):
    Curriculum(window=0, rule="progress")

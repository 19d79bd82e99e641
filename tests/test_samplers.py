"""Samplers against their formulas by statistics (100,000 draws)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from scenes import samplers
from scenes.samplers import Ranges
from scenes.staircase import STAIR_RANGES

N = 100_000
# Wide ranges so that clipping never binds: the raw formula is what is measured.
WIDE = Ranges(names=("a", "b"), low=(0.0, 10.0), high=(1000.0, 410.0), integer=(False, False),
              shrinking=(False, True))


def _draw(fn, key=0):
  keys = jax.random.split(jax.random.PRNGKey(key), N)
  return np.asarray(jax.jit(jax.vmap(fn))(keys))


@pytest.mark.parametrize("eps", [0.1, 0.3, 0.6])  # bounds >= 16 sigma away: no clipping
def test_paper_incremental_matches_mean_and_variance(eps):
  x = _draw(lambda k: samplers.incremental(k, jnp.float32(eps), WIDE, "paper"))
  lo, delta = np.array(WIDE.low), WIDE.delta
  mean, var = lo + eps * delta, eps * delta
  se = np.sqrt(var / N)
  np.testing.assert_array_less(np.abs(x.mean(0) - mean), 5 * se)
  np.testing.assert_allclose(x.var(0), var, rtol=0.03)


@pytest.mark.parametrize("eps", [0.2, 0.4])  # bounds >= 6 sigma away
def test_original_incremental_shrinks_marked_components(eps):
  x = _draw(lambda k: samplers.incremental(k, jnp.float32(eps), WIDE, "original"))
  lo, delta = np.array(WIDE.low), WIDE.delta
  mean = lo + np.array([eps, 1 - eps]) * delta
  std = eps * delta / 4
  np.testing.assert_array_less(np.abs(x.mean(0) - mean), 5 * std / np.sqrt(N))
  np.testing.assert_allclose(x.std(0), std, rtol=0.02)


@pytest.mark.parametrize("variant", ["paper", "original"])
@pytest.mark.parametrize("eps", [0.0, 0.25, 0.5, 1.0])
def test_stair_samples_never_leave_ranges_and_steps_are_integers(eps, variant):
  x = _draw(lambda k: samplers.incremental(k, jnp.float32(eps), STAIR_RANGES, variant))
  assert (x >= np.array(STAIR_RANGES.low) - 1e-6).all() and (x <= np.array(STAIR_RANGES.high) + 1e-6).all()
  np.testing.assert_array_equal(x[:, 2], np.round(x[:, 2]))


def test_eps_zero_gives_xi_min_exactly():
  x = _draw(lambda k: samplers.incremental(k, jnp.float32(0.0), STAIR_RANGES, "paper"))
  np.testing.assert_array_equal(x, np.broadcast_to(np.array(STAIR_RANGES.low, np.float32), x.shape))


def test_uniform_matches_its_moments_and_integer_frequencies():
  x = _draw(lambda k: samplers.uniform(k, STAIR_RANGES))
  lo, hi = np.array(STAIR_RANGES.low[:2]), np.array(STAIR_RANGES.high[:2])
  np.testing.assert_allclose(x[:, :2].mean(0), (lo + hi) / 2, rtol=0.01)
  np.testing.assert_allclose(x[:, :2].var(0), (hi - lo) ** 2 / 12, rtol=0.03)
  counts = np.bincount(x[:, 2].astype(int), minlength=8)[1:]
  np.testing.assert_allclose(counts / N, 1 / 7, atol=0.006)
  assert counts.sum() == N


def test_bad_sampler_input_fails_clearly():
  with pytest.raises(ValueError, match="unknown sampler"):
    samplers.sample(jax.random.PRNGKey(0), 0.5, STAIR_RANGES, "gaussian")
  with pytest.raises(ValueError, match="unknown incremental variant"):
    samplers.incremental(jax.random.PRNGKey(0), 0.5, STAIR_RANGES, "mine")
  with pytest.raises(ValueError, match="min"):
    Ranges(names=("a",), low=(2.0,), high=(1.0,), integer=(False,), shrinking=(False,))

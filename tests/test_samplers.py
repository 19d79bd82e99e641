"""Samplers against their formulas by statistics (100,000 draws)."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from mjx_tracks.envs.config import default_config
from scenes import samplers
from scenes.samplers import Ranges
from scenes.staircase import stair_ranges

N = 100_000
# Wide ranges so that clipping never binds: the raw formula is what is measured.
WIDE = Ranges(names=("a", "b"), low=(0.0, 10.0), high=(1000.0, 410.0), integer=(False, False),
              hard=("high", "low"))
_S = default_config().scene
STAIRS = stair_ranges(_S.tread, _S.riser, _S.steps)


def _draw(fn, key=0):
  keys = jax.random.split(jax.random.PRNGKey(key), N)
  return np.asarray(jax.jit(jax.vmap(fn))(keys))


def _phi(x):
  return 0.5 * (1 + math.erf(x / math.sqrt(2)))


@pytest.mark.parametrize("variant", ["difficulty", "paper_literal"])
@pytest.mark.parametrize("eps", [0.1, 0.3, 0.6])  # bounds >= 16 sigma away: no clipping
def test_eq6_matches_mean_and_variance_in_its_coordinates(eps, variant):
  x = _draw(lambda k: samplers.incremental(k, jnp.float32(eps), WIDE, variant))
  lo, hi, delta = np.array(WIDE.low), np.array(WIDE.high), WIDE.delta
  if variant == "paper_literal":  # eq. 6 as printed: both components move up from xi_min
    mean = lo + eps * delta
  else:  # difficulty coordinates: "a" moves up from its low end, "b" (hard low) down from its high end
    mean = np.array([lo[0] + eps * delta[0], hi[1] - eps * delta[1]])
  var = eps * delta
  np.testing.assert_array_less(np.abs(x.mean(0) - mean), 5 * np.sqrt(var / N))
  np.testing.assert_allclose(x.var(0), var, rtol=0.03)


@pytest.mark.parametrize("eps", [0.2, 0.4])  # bounds >= 6 sigma away
def test_original_code_variant_moves_toward_the_hard_ends_with_a_quarter_sigma(eps):
  x = _draw(lambda k: samplers.incremental(k, jnp.float32(eps), WIDE, "original_code"))
  lo, hi, delta = np.array(WIDE.low), np.array(WIDE.high), WIDE.delta
  mean = np.array([lo[0] + eps * delta[0], hi[1] - eps * delta[1]])
  std = eps * delta / 4
  np.testing.assert_array_less(np.abs(x.mean(0) - mean), 5 * std / np.sqrt(N))
  np.testing.assert_allclose(x.std(0), std, rtol=0.02)


def test_difficulty_variant_at_eps_one_centres_on_the_hardest_staircase():
  """The Gaussian's mean is the hardest configuration, so after clipping the hardest value of
  each parameter holds P(z >= -c / sigma) of the draws (c = 0 continuous, 0.5 for rounded steps)."""
  assert tuple(STAIRS.hardest) == pytest.approx((_S.tread[0], _S.riser[1], _S.steps[1]))
  mean, std = samplers.gaussian_moments(jnp.float32(1.0), STAIRS, "difficulty")
  np.testing.assert_allclose(np.asarray(mean), STAIRS.hardest, rtol=1e-6)
  x = _draw(lambda k: samplers.incremental(k, jnp.float32(1.0), STAIRS, "difficulty"))
  at_hard = (x == STAIRS.hardest).mean(0)
  sigma = np.asarray(std)
  expected = [0.5, 0.5, _phi(0.5 / sigma[2])]
  np.testing.assert_allclose(at_hard, expected, atol=5 * np.sqrt(0.25 / N))
  literal = _draw(lambda k: samplers.incremental(k, jnp.float32(1.0), STAIRS, "paper_literal"))
  assert (literal[:, 0] == STAIRS.hardest[0]).mean() < 0.4  # as printed, treads centre on the longest


@pytest.mark.parametrize("variant", samplers.VARIANTS)
def test_eps_zero_gives_the_easiest_end(variant):
  x = _draw(lambda k: samplers.incremental(k, jnp.float32(0.0), STAIRS, variant))
  easy = np.array(STAIRS.low, np.float32) if variant == "paper_literal" else STAIRS.easiest
  np.testing.assert_array_equal(x, np.broadcast_to(easy, x.shape))


@pytest.mark.parametrize("variant", samplers.VARIANTS)
@pytest.mark.parametrize("eps", [0.25, 0.5, 1.0])
def test_stair_samples_never_leave_ranges_and_steps_are_integers(eps, variant):
  x = _draw(lambda k: samplers.incremental(k, jnp.float32(eps), STAIRS, variant))
  assert (x >= np.array(STAIRS.low) - 1e-6).all() and (x <= np.array(STAIRS.high) + 1e-6).all()
  np.testing.assert_array_equal(x[:, 2], np.round(x[:, 2]))


def test_uniform_matches_its_moments_and_integer_frequencies():
  x = _draw(lambda k: samplers.uniform(k, STAIRS))
  lo, hi = np.array(STAIRS.low[:2]), np.array(STAIRS.high[:2])
  np.testing.assert_allclose(x[:, :2].mean(0), (lo + hi) / 2, rtol=0.01)
  np.testing.assert_allclose(x[:, :2].var(0), (hi - lo) ** 2 / 12, rtol=0.03)
  n_lo, n_hi = int(STAIRS.low[2]), int(STAIRS.high[2])
  counts = np.bincount(x[:, 2].astype(int), minlength=n_hi + 1)[n_lo:]
  np.testing.assert_allclose(counts / N, 1 / (n_hi - n_lo + 1), atol=0.006)
  assert counts.sum() == N


def test_bad_sampler_input_fails_clearly():
  with pytest.raises(ValueError, match="unknown sampler"):
    samplers.sample(jax.random.PRNGKey(0), 0.5, STAIRS, "gaussian", "difficulty")
  with pytest.raises(ValueError, match="unknown incremental variant"):
    samplers.incremental(jax.random.PRNGKey(0), 0.5, STAIRS, "mine")
  with pytest.raises(ValueError, match="min"):
    Ranges(names=("a",), low=(2.0,), high=(1.0,), integer=(False,), hard=("high",))
  with pytest.raises(ValueError, match="hard end"):
    Ranges(names=("a",), low=(1.0,), high=(2.0,), integer=(False,), hard=("up",))

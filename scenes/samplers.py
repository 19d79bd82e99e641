"""Scene-parameter samplers xi ~ p(xi | eps): uniform and incremental Gaussian (paper eq. 6a/6b).

Pure JAX functions of (key, eps, ranges); vmap them over keys for a batch.

Uniform:      xi_i ~ U(xi_min_i, xi_max_i); integer components ~ U{min..max}.
Incremental (paper, eq. 6a/6b):
              xi ~ N(xi_min + eps * Delta, eps * diag(Delta)),  Delta = xi_max - xi_min,
              i.e. mean_i = xi_min_i + eps Delta_i and variance_i = eps Delta_i;
              then clipped to [xi_min, xi_max]; integer components rounded.
Incremental (the original's code, `variant="original"`):
              sigma_i = eps Delta_i / 4; mean_i = xi_min_i + eps Delta_i, except components listed
              as `shrinking` (staircase tread), whose mean is xi_min_i + (1 - eps) Delta_i, so that
              treads shrink, i.e. get harder, as eps grows.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np


@dataclasses.dataclass(frozen=True)
class Ranges:
  """Named ranges of a parameter vector xi; integer components are rounded."""

  names: tuple[str, ...]
  low: tuple[float, ...]
  high: tuple[float, ...]
  integer: tuple[bool, ...]
  shrinking: tuple[bool, ...]  # harder when smaller (used by the original's variant)

  def __post_init__(self):
    n = len(self.names)
    if not (len(self.low) == len(self.high) == len(self.integer) == len(self.shrinking) == n):
      raise ValueError("Ranges fields must have one entry per name")
    for name, lo, hi in zip(self.names, self.low, self.high):
      if not lo <= hi:
        raise ValueError(f"range of {name!r} has min {lo} > max {hi}")

  @property
  def delta(self) -> np.ndarray:
    return np.asarray(self.high, np.float32) - np.asarray(self.low, np.float32)


def _finish(xi: jax.Array, r: Ranges) -> jax.Array:
  lo, hi = jnp.asarray(r.low, jnp.float32), jnp.asarray(r.high, jnp.float32)
  xi = jnp.clip(xi, lo, hi)
  return jnp.where(jnp.asarray(r.integer), jnp.round(xi), xi)


def uniform(key: jax.Array, r: Ranges) -> jax.Array:
  """xi_i ~ U(min, max); integer components uniform over {min, ..., max}."""
  lo, hi = jnp.asarray(r.low, jnp.float32), jnp.asarray(r.high, jnp.float32)
  u = jax.random.uniform(key, lo.shape)
  integer = jnp.asarray(r.integer)
  cont = lo + u * (hi - lo)
  disc = jnp.floor(lo + u * (hi - lo + 1.0))
  return _finish(jnp.where(integer, disc, cont), r)


def incremental(key: jax.Array, eps: jax.Array, r: Ranges, variant: str = "paper") -> jax.Array:
  """Incremental Gaussian sample at difficulty eps in [0, 1] (formulas in the module docstring)."""
  lo = jnp.asarray(r.low, jnp.float32)
  delta = jnp.asarray(r.delta)
  eps = jnp.clip(eps, 0.0, 1.0)
  z = jax.random.normal(key, lo.shape)
  if variant == "paper":
    mean, std = lo + eps * delta, jnp.sqrt(eps * delta)
  elif variant == "original":
    frac = jnp.where(jnp.asarray(r.shrinking), 1.0 - eps, eps)
    mean, std = lo + frac * delta, eps * delta / 4.0
  else:
    raise ValueError(f"unknown incremental variant {variant!r}; use 'paper' or 'original'")
  return _finish(mean + std * z, r)


SAMPLERS = ("uniform", "incremental")


def sample(key: jax.Array, eps: jax.Array, r: Ranges, sampler: str, variant: str = "paper") -> jax.Array:
  """Dispatches on the (static) sampler name."""
  if sampler == "uniform":
    return uniform(key, r)
  if sampler == "incremental":
    return incremental(key, eps, r, variant)
  raise ValueError(f"unknown sampler {sampler!r}; known: {SAMPLERS}")

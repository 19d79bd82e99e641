"""Scene-parameter samplers xi ~ p(xi | eps): uniform and incremental Gaussian (paper eq. 6a/6b).

Pure JAX functions of (key, eps, ranges); vmap them over keys for a batch.

Every parameter declares its *hard end* (`hard`: "low" or "high"; e.g. a staircase's tread is
hardest short, its riser tall). Difficulty coordinates measure each parameter from its easy end:
d_i = |xi_i - easy_i| in [0, Delta_i], Delta_i = xi_max_i - xi_min_i, so d = 0 is the easiest and
d = Delta the hardest configuration.

Uniform:       xi_i ~ U(xi_min_i, xi_max_i); integer components ~ U{min..max}.
Incremental, variant `difficulty` (configs/defaults.yaml): paper eq. 6 in difficulty coordinates,
               d ~ N(eps Delta, eps diag(Delta)), clipped to [0, Delta], xi = easy + d toward hard;
               eps = 0 gives the easiest configuration, eps = 1 centres on the hardest.
Incremental, variant `paper_literal`: eq. 6 as printed,
               xi ~ N(xi_min + eps Delta, eps diag(Delta)), clipped to [xi_min, xi_max]; eps = 1
               centres on xi_max whatever the hard end (for stairs: the longest, easiest tread).
Incremental, variant `original_code`: the original's code, difficulty-coordinate mean eps Delta
               with a narrower sigma = eps Delta / 4.
Integer components are rounded after clipping.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

SAMPLERS = ("uniform", "incremental")
VARIANTS = ("difficulty", "paper_literal", "original_code")
HARD_ENDS = ("low", "high")


@dataclasses.dataclass(frozen=True)
class Ranges:
  """Named ranges of a parameter vector xi, each with its hard end; integer components are rounded."""

  names: tuple[str, ...]
  low: tuple[float, ...]
  high: tuple[float, ...]
  integer: tuple[bool, ...]
  hard: tuple[str, ...]  # per component: "low" (harder when smaller) or "high"

  def __post_init__(self):
    n = len(self.names)
    if not (len(self.low) == len(self.high) == len(self.integer) == len(self.hard) == n):
      raise ValueError("Ranges fields must have one entry per name")
    for name, lo, hi, end in zip(self.names, self.low, self.high, self.hard):
      if not lo <= hi:
        raise ValueError(f"range of {name!r} has min {lo} > max {hi}")
      if end not in HARD_ENDS:
        raise ValueError(f"hard end of {name!r} must be one of {HARD_ENDS}, got {end!r}")

  @property
  def delta(self) -> np.ndarray:
    return np.asarray(self.high, np.float32) - np.asarray(self.low, np.float32)

  @property
  def direction(self) -> np.ndarray:
    """+1 where larger is harder, -1 where smaller is harder."""
    return np.where(np.asarray(self.hard) == "high", 1.0, -1.0).astype(np.float32)

  @property
  def easiest(self) -> np.ndarray:
    return np.where(self.direction > 0, self.low, self.high).astype(np.float32)

  @property
  def hardest(self) -> np.ndarray:
    return np.where(self.direction > 0, self.high, self.low).astype(np.float32)


def _finish(xi: jax.Array, r: Ranges) -> jax.Array:
  lo, hi = jnp.asarray(r.low, jnp.float32), jnp.asarray(r.high, jnp.float32)
  xi = jnp.clip(xi, lo, hi)
  return jnp.where(jnp.asarray(r.integer), jnp.round(xi), xi)


def uniform(key: jax.Array, r: Ranges) -> jax.Array:
  """xi_i ~ U(min, max); integer components uniform over {min, ..., max}."""
  lo, hi = jnp.asarray(r.low, jnp.float32), jnp.asarray(r.high, jnp.float32)
  u = jax.random.uniform(key, lo.shape)
  cont = lo + u * (hi - lo)
  disc = jnp.floor(lo + u * (hi - lo + 1.0))
  return _finish(jnp.where(jnp.asarray(r.integer), disc, cont), r)


def gaussian_moments(eps: jax.Array, r: Ranges, variant: str) -> tuple[jax.Array, jax.Array]:
  """(mean, std) of the unclipped Gaussian of a variant at difficulty eps, in xi's own units."""
  if variant not in VARIANTS:
    raise ValueError(f"unknown incremental variant {variant!r}; known: {VARIANTS}")
  eps = jnp.clip(eps, 0.0, 1.0)
  delta = jnp.asarray(r.delta)
  if variant == "paper_literal":
    return jnp.asarray(r.low, jnp.float32) + eps * delta, jnp.sqrt(eps * delta)
  mean = jnp.asarray(r.easiest) + jnp.asarray(r.direction) * eps * delta
  std = jnp.sqrt(eps * delta) if variant == "difficulty" else eps * delta / 4.0
  return mean, std


def incremental(key: jax.Array, eps: jax.Array, r: Ranges, variant: str) -> jax.Array:
  """Incremental Gaussian sample at difficulty eps in [0, 1] (formulas in the module docstring)."""
  mean, std = gaussian_moments(eps, r, variant)
  return _finish(mean + std * jax.random.normal(key, mean.shape), r)


def sample(key: jax.Array, eps: jax.Array, r: Ranges, sampler: str, variant: str) -> jax.Array:
  """Dispatches on the (static) sampler name; variant is the incremental one (unused by uniform)."""
  if sampler == "uniform":
    return uniform(key, r)
  if sampler == "incremental":
    return incremental(key, eps, r, variant)
  raise ValueError(f"unknown sampler {sampler!r}; known: {SAMPLERS}")

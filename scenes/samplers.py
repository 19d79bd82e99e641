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

A `Draw` is a sampler and its ranges as data (array bounds, a uniform flag): one compiled program
draws any of them (every evaluation scene of a kind: uniform, incremental, hardest, a held-out
configuration as a range of width 0), where `sample` takes them as constants of the program.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct

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


@struct.dataclass
class Draw:
  """A sampler and its ranges as data: xi ~ U(low, high) if uniform, else the incremental sampler
  on [low, high] (the hard ends and integer components stay those of the kind's Ranges); for
  staircases, also the direction (ascent)."""

  low: jax.Array  # (k,) xi_min
  high: jax.Array  # (k,) xi_max
  uniform: jax.Array  # () bool: the uniform sampler, else the incremental one
  kinds: jax.Array | None = None  # (K,) bool: the sub-kinds (terrain kinds, areas) an episode may draw; None: all
  ascent: jax.Array | None = None  # () bool: a staircase climbed, else descended; None: the generator's own direction


def as_draw(r: Ranges, sampler: str, kinds=None) -> Draw:
  """The draw of sampler over r, as data; kinds: which of the generator's sub-kinds it may draw."""
  if sampler not in SAMPLERS:
    raise ValueError(f"unknown sampler {sampler!r}; known: {SAMPLERS}")
  return Draw(low=jnp.asarray(r.low, jnp.float32), high=jnp.asarray(r.high, jnp.float32),
              uniform=jnp.bool_(sampler == "uniform"), kinds=None if kinds is None else jnp.asarray(kinds, bool))


def pick_kind(key: jax.Array, n: int, draw: Draw | None = None) -> jax.Array:
  """A sub-kind index ~ U{0..n-1}; with a draw's kinds, uniform over those it allows (the same index
  from the same key where it allows all)."""
  if draw is None or draw.kinds is None:
    return jax.random.randint(key, (), 0, n)
  i = jax.random.randint(key, (), 0, jnp.sum(draw.kinds))
  return jnp.nonzero(draw.kinds, size=n)[0][i]


def _finish(xi: jax.Array, r: Ranges, lo: jax.Array, hi: jax.Array) -> jax.Array:
  """xi clipped to [lo, hi], its integer components rounded."""
  xi = jnp.clip(xi, lo, hi)
  return jnp.where(jnp.asarray(r.integer), jnp.round(xi), xi)


def _uniform(key: jax.Array, r: Ranges, lo: jax.Array, hi: jax.Array) -> jax.Array:
  u = jax.random.uniform(key, lo.shape)
  cont = lo + u * (hi - lo)
  disc = jnp.floor(lo + u * (hi - lo + 1.0))
  return _finish(jnp.where(jnp.asarray(r.integer), disc, cont), r, lo, hi)


def uniform(key: jax.Array, r: Ranges) -> jax.Array:
  """xi_i ~ U(min, max); integer components uniform over {min, ..., max}."""
  return _uniform(key, r, jnp.asarray(r.low, jnp.float32), jnp.asarray(r.high, jnp.float32))


def _moments(eps: jax.Array, r: Ranges, variant: str, lo: jax.Array, hi: jax.Array) -> tuple[jax.Array, jax.Array]:
  if variant not in VARIANTS:
    raise ValueError(f"unknown incremental variant {variant!r}; known: {VARIANTS}")
  eps = jnp.clip(eps, 0.0, 1.0)
  delta = hi - lo
  if variant == "paper_literal":
    return lo + eps * delta, jnp.sqrt(eps * delta)
  direction = jnp.asarray(r.direction)
  mean = jnp.where(direction > 0, lo, hi) + direction * eps * delta  # from the easy end toward the hard one
  std = jnp.sqrt(eps * delta) if variant == "difficulty" else eps * delta / 4.0
  return mean, std


def gaussian_moments(eps: jax.Array, r: Ranges, variant: str) -> tuple[jax.Array, jax.Array]:
  """(mean, std) of the unclipped Gaussian of a variant at difficulty eps, in xi's own units."""
  return _moments(eps, r, variant, jnp.asarray(r.low, jnp.float32), jnp.asarray(r.high, jnp.float32))


def _incremental(key: jax.Array, eps: jax.Array, r: Ranges, variant: str, lo: jax.Array, hi: jax.Array) -> jax.Array:
  mean, std = _moments(eps, r, variant, lo, hi)
  return _finish(mean + std * jax.random.normal(key, mean.shape), r, lo, hi)


def incremental(key: jax.Array, eps: jax.Array, r: Ranges, variant: str) -> jax.Array:
  """Incremental Gaussian sample at difficulty eps in [0, 1] (formulas in the module docstring)."""
  return _incremental(key, eps, r, variant, jnp.asarray(r.low, jnp.float32), jnp.asarray(r.high, jnp.float32))


def sample(key: jax.Array, eps: jax.Array, r: Ranges, sampler: str, variant: str, draw: Draw | None = None) -> jax.Array:
  """Dispatches on the (static) sampler name; variant is the incremental one (unused by uniform).
  With a draw, its sampler and bounds (data) replace sampler and r's bounds (r keeps the hard ends
  and integer components): both samplers are computed, and the draw's flag picks one."""
  if draw is not None:
    lo, hi = draw.low, draw.high
    return jnp.where(draw.uniform, _uniform(key, r, lo, hi), _incremental(key, eps, r, variant, lo, hi))
  if sampler == "uniform":
    return uniform(key, r)
  if sampler == "incremental":
    return incremental(key, eps, r, variant)
  raise ValueError(f"unknown sampler {sampler!r}; known: {SAMPLERS}")

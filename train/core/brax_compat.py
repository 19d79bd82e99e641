"""Brax 0.14.2 on JAX >= 0.10 (only for train.core.brax_reference): a replacement for the removed `jax.device_put_replicated`.

Brax's PPO and SAC trainers replicate their training state with `jax.device_put_replicated`
(google/brax issue 671). This puts a stacked copy of each leaf on a one-axis device mesh with a
NamedSharding, which pmap consumes as a per-device leading axis. Remove once Brax is fixed.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from jax.sharding import Mesh, NamedSharding, PartitionSpec


def device_put_replicated(x, devices):
  """Replicates every leaf of x onto devices along a new leading axis."""
  devices = list(devices)
  sharding = NamedSharding(Mesh(np.array(devices), ("devices",)), PartitionSpec("devices"))

  def put(a):
    a = jnp.asarray(a)
    return jax.device_put(jnp.broadcast_to(a, (len(devices),) + a.shape), sharding)

  return jax.tree_util.tree_map(put, x)


def install() -> bool:
  """Installs the replacement if JAX lacks the function; returns whether it did."""
  if hasattr(jax, "device_put_replicated"):
    return False
  jax.device_put_replicated = device_put_replicated
  return True

"""The device mesh of a training run: the environment batch sharded over every device (of every
process, under `jax.distributed`), everything else replicated; and moving whole states between
the mesh and the host (for checkpoints)."""

from __future__ import annotations

import jax
import numpy as np
from brax.envs.base import Wrapper
from jax.experimental import multihost_utils
from jax.sharding import Mesh, NamedSharding, PartitionSpec

BATCH = "batch"  # the mesh axis the environments are split along


def make_mesh() -> Mesh:
  """A one-axis mesh over all devices of all processes."""
  return Mesh(np.array(jax.devices()), (BATCH,))


def state_shardings(state, mesh: Mesh):
  """Shardings for a learner state: leaves of `state.env_state` split along their first (batch)
  axis, all others (parameters, optimizer, normalizer, replay buffer, keys) replicated."""
  shard = jax.tree_util.tree_map(lambda _: replicated(mesh), state)
  return shard.replace(env_state=batch_shardings(state.env_state, mesh))


def batch_shardings(tree, mesh: Mesh):
  """Shardings for a tree of batched values: leaves split along their first (batch) axis, scalars replicated."""
  return jax.tree_util.tree_map(lambda x: NamedSharding(mesh, _spec(x)), tree)


def split_along_batch(mesh: Mesh) -> NamedSharding:
  """An array split along its first (batch) axis over the mesh."""
  return NamedSharding(mesh, PartitionSpec(BATCH))


def batch_specs(tree):
  """The partition of each leaf of a tree of batched values: its first axis along BATCH, scalars whole."""
  return jax.tree_util.tree_map(_spec, tree)


def _spec(x) -> PartitionSpec:
  return PartitionSpec(BATCH) if np.ndim(x) else PartitionSpec()


def each_device(fn, mesh: Mesh):
  """fn of batched arguments, with a batched result, run by each device on its own part of the
  batch (`jax.shard_map`, as ShardedStep does for the env's step)."""
  def run(*args):
    return jax.shard_map(fn, mesh=mesh, in_specs=batch_specs(args), out_specs=PartitionSpec(BATCH),
                         check_vma=False)(*args)
  return run


class ShardedStep(Wrapper):
  """Runs a batched env's step on each device's own part of the batch (`jax.shard_map`).

  Under plain `jax.jit` the partitioner keeps the batch as one array: every data-dependent loop
  exit inside the step (MJX's solver iterations, its line search) is then reduced across devices,
  a synchronisation per iteration. Here each device loops on its own robots, and only the
  curriculum's reduction (the env built with `axis_name=BATCH`) crosses devices."""

  def __init__(self, env, mesh: Mesh):
    super().__init__(env)
    self.mesh = mesh

  def step_on(self, state, action):
    """The wrapped env's step_on (mjx_tracks.envs.wrappers.CurriculumAutoReset) on each device's part."""
    return each_device(self.env.step_on, self.mesh)(state, action)

  def reset_where_done(self, nstate, glob):
    """The wrapped env's reset_where_done on each device's part."""
    return each_device(self.env.reset_where_done, self.mesh)(nstate, glob)

  def step(self, state, action):
    specs = batch_specs(state)
    step = jax.shard_map(self.env.step, mesh=self.mesh, in_specs=(specs, PartitionSpec(BATCH)),
                         out_specs=specs, check_vma=False)
    return step(state, action)


def use_gspmd_partitioner() -> None:
  """Partition with GSPMD, not Shardy (JAX's default): with Shardy, XLA's GPU compiler (jaxlib
  0.11.2, 2 H200s) segfaults on MJX's step under shard_map, even with no collective in it; with
  GSPMD it compiles and gives the same rewards (`scripts/gpu/probe_shardmap.py`)."""
  jax.config.update("jax_use_shardy_partitioner", False)


def replicated(mesh: Mesh) -> NamedSharding:
  return NamedSharding(mesh, PartitionSpec())


def to_host(tree):
  """A tree of global arrays -> numpy on every process (gathers shards held by other processes)."""
  if jax.process_count() == 1:
    return jax.device_get(tree)
  return multihost_utils.process_allgather(tree, tiled=True)


def from_host(tree, shardings):
  """A tree of numpy arrays (the same on every process) -> global arrays with the given shardings."""
  def put(x, sharding):
    x = np.asarray(x)
    return jax.make_array_from_callback(x.shape, sharding, lambda index: x[index])
  return jax.tree_util.tree_map(put, tree, shardings)


def local_value(x):
  """A replicated global array's value, readable on any process."""
  return np.asarray(x.addressable_data(0)) if isinstance(x, jax.Array) else np.asarray(x)

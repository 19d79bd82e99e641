"""Compiles (then runs) variants of the task's batched env step on all visible devices, to find
which one crashes XLA's compiler; each variant in its own process, since a crash is a segfault.

  python scripts/gpu/probe_shardmap.py VARIANT [NUM_ENVS]
  gspmd     plain jit of the batched step (the partitioner splits the batch)
  nogather  the step under shard_map (train.core.mesh.ShardedStep), curriculum per device
  gather    the same, the curriculum reduced across devices (what training runs)
  cho       shard_map of a batched Cholesky factorization alone

On 2 H200s with jaxlib 0.11.2, `nogather` and `gather` segfault with JAX's default partitioner
(Shardy) and pass with JAX_USE_SHARDY_PARTITIONER=0; `gspmd` and `cho` pass with either.
"""

from __future__ import annotations

import sys
import time

import jax
import jax.numpy as jnp
import numpy as np
from jax.sharding import Mesh, NamedSharding, PartitionSpec

import mjx_tracks  # noqa: F401  (quiet MJX import)
from mjx_tracks.envs.config import load_config
from mjx_tracks.envs.task_env import TrackedRobotEnv
from mjx_tracks.envs.wrappers import batched_env
from train.core.mesh import BATCH, ShardedStep


def cholesky(mesh: Mesh, n: int) -> float:
  """Sum of the factors of n random 20 x 20 SPD matrices, factored per device."""
  a = jax.random.normal(jax.random.PRNGKey(0), (n, 20, 20))
  a = jnp.einsum("bij,bkj->bik", a, a) + 20 * jnp.eye(20)
  f = jax.shard_map(jax.vmap(lambda x: jax.scipy.linalg.cho_factor(x)[0]), mesh=mesh,
                    in_specs=PartitionSpec(BATCH), out_specs=PartitionSpec(BATCH), check_vma=False)
  return float(jnp.sum(jax.jit(f)(a)))


def env_step(mesh: Mesh, variant: str, n: int) -> float:
  """Sum of the rewards of one zero-action step of n robots; prints the compile time."""
  env = batched_env(TrackedRobotEnv(load_config("asc-inc-cog", ())), axis_name=BATCH if variant == "gather" else None)
  if variant != "gspmd":
    env = ShardedStep(env, mesh)
  batch = NamedSharding(mesh, PartitionSpec(BATCH))
  state = jax.jit(env.reset, out_shardings=batch)(jax.random.split(jax.random.PRNGKey(0), n))
  action = jax.device_put(jnp.zeros((n, env.action_size)), batch)
  t0 = time.time()
  step = jax.jit(env.step).lower(state, action).compile()
  print(f"{variant}: compiled in {time.time() - t0:.1f} s", flush=True)
  return float(jnp.sum(step(state, action).reward))


def main(variant: str, n: int) -> None:
  mesh = Mesh(np.array(jax.devices()), (BATCH,))
  print(f"{variant} on {mesh.devices.size} x {jax.default_backend()}, shardy {jax.config.jax_use_shardy_partitioner}")
  total = cholesky(mesh, n) if variant == "cho" else env_step(mesh, variant, n)
  print(f"{variant}: ran, sum {total:.6g}")


if __name__ == "__main__":
  main(sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else 8192)

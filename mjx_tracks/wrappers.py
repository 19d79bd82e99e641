"""Batch-level auto-reset that keeps the curriculum running (replaces Brax's AutoResetWrapper).

Brax's AutoResetWrapper restores each environment's first state, so every episode would replay the
scene drawn at the start. Here, after each batched step, the global curriculum state (eps from the
last N_e finished episodes) and the penalty normalizer are updated from the done mask, outside the
per-environment vmap, and every finished environment gets a new scene drawn at the new eps.
The global state is kept, identical, in every environment's info (Brax expects batched leaves).
"""

from __future__ import annotations

from typing import Optional

import jax
import jax.numpy as jnp
from brax.envs.base import State, Wrapper
from brax.envs.wrappers.training import EpisodeWrapper, VmapWrapper
from flax import struct

from mjx_tracks.env import TrackedRobotEnv
from mjx_tracks.monitor import PenaltyNormalizer, normalizer_init, normalizer_update
from scenes.curriculum import CurriculumState


@struct.dataclass
class GlobalStats:
  curriculum: CurriculumState
  normalizer: PenaltyNormalizer


class CurriculumAutoReset(Wrapper):
  """Wraps a batched (Vmap + Episode) env of a TrackedRobotEnv."""

  def __init__(self, env, core: TrackedRobotEnv, axis_name: Optional[str] = None):
    super().__init__(env)
    self.core = core
    self.axis_name = axis_name

  def reset(self, rng: jax.Array) -> State:
    state = self.env.reset(rng)
    n = rng.shape[0]
    glob = GlobalStats(self.core.curriculum.init(), normalizer_init(self.core.cfg.reward))
    state.info["global"] = jax.tree_util.tree_map(lambda x: jnp.broadcast_to(x, (n,) + x.shape), glob)
    state.info["reset_key"] = jax.vmap(lambda k: jax.random.fold_in(k, 7))(rng)
    state.info["final_obs"] = state.obs
    return state

  def step(self, state: State, action: jax.Array) -> State:
    if "steps" in state.info:
      state.info["steps"] = jnp.where(state.done, 0, state.info["steps"])
    state = state.replace(done=jnp.zeros_like(state.done))
    nstate = self.env.step(state, action)
    done = nstate.done.astype(bool)
    glob: GlobalStats = jax.tree_util.tree_map(lambda x: x[0], nstate.info["global"])
    ep = nstate.info["episode_metrics"]
    cur = self.core.curriculum.update(glob.curriculum, done, ep["sum_reward"], ep["progress"],
                                      self.axis_name)
    penalty_sums = nstate.pipeline_state.penalty_sum
    if self.axis_name is not None:
      gather = lambda x: jax.lax.all_gather(x, self.axis_name, tiled=True)
      norm = normalizer_update(self.core.cfg.reward, glob.normalizer, gather(done), gather(penalty_sums))
    else:
      norm = normalizer_update(self.core.cfg.reward, glob.normalizer, done, penalty_sums)
    split = jax.vmap(jax.random.split)(nstate.info["reset_key"])
    fresh = jax.vmap(self.core.reset_at, in_axes=(0, None, None))(split[:, 0], cur.eps, norm.k)

    def where_done(new, old):
      mask = done.reshape(done.shape + (1,) * (new.ndim - done.ndim))
      return jnp.where(mask, new, old)

    es = jax.tree_util.tree_map(where_done, fresh.pipeline_state, nstate.pipeline_state)
    es = es.replace(penalty_k=jnp.broadcast_to(norm.k, es.penalty_k.shape))
    n = done.shape[0]
    nstate.info["global"] = jax.tree_util.tree_map(
        lambda x: jnp.broadcast_to(x, (n,) + x.shape), GlobalStats(cur, norm))
    nstate.info["reset_key"] = split[:, 1]
    nstate.info["final_obs"] = nstate.obs
    nstate.info["eps"] = jnp.broadcast_to(cur.eps, (n,))
    return nstate.replace(pipeline_state=es, obs=where_done(fresh.obs, nstate.obs))


def wrap_for_training(core: TrackedRobotEnv, axis_name: Optional[str] = None):
  """A `wrap_env_fn` for brax.training.agents.{ppo,sac}.train: Vmap -> Episode -> curriculum reset."""

  def wrap(env, episode_length: int = 1000, action_repeat: int = 1, randomization_fn=None, **_):
    if randomization_fn is not None:
      raise ValueError("mjx_tracks environments randomize their scenes themselves; "
                       "randomization_fn is not supported")
    inner = EpisodeWrapper(VmapWrapper(env), episode_length, action_repeat)
    return CurriculumAutoReset(inner, core, axis_name)

  return wrap


def batched_env(core: TrackedRobotEnv, axis_name: Optional[str] = None):
  """The task's batched environment with its own episode length and curriculum reset."""
  return wrap_for_training(core, axis_name)(core, core.cfg.episode.max_steps, 1)

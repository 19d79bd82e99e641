"""Batch-level auto-reset that keeps the curriculum running (replaces Brax's AutoResetWrapper).

Brax's AutoResetWrapper restores each environment's first state, so every episode would replay the
scene drawn at the start. Here, after each batched step, the global curriculum state (eps from the
last N_e finished episodes) and the penalty normalizer are updated from the done mask, outside the
per-environment vmap, and every finished environment gets a new scene drawn at the new eps.
The global state is kept, identical, in every environment's info (Brax expects batched leaves).
"""

from __future__ import annotations

import dataclasses
from typing import Callable, Optional

import jax
import jax.numpy as jnp
import numpy as np
from brax.envs.base import State, Wrapper
from brax.envs.wrappers.training import EpisodeWrapper, VmapWrapper
from flax import struct

from mjx_tracks.envs.task_env import TrackedRobotEnv
from mjx_tracks.envs.rewards import PenaltyNormalizer, normalizer_init, normalizer_update
from scenes.curriculum import CurriculumState


@struct.dataclass
class GlobalStats:
  curriculum: CurriculumState
  normalizer: PenaltyNormalizer


class CurriculumAutoReset(Wrapper):
  """Wraps a batched (Vmap + Episode) env of a TrackedRobotEnv."""

  def __init__(self, env, core: TrackedRobotEnv, axis_name: Optional[str] = None,
               initial: Optional[GlobalStats] = None, report: Optional[Callable] = None):
    super().__init__(env)
    self.core = core
    self.axis_name = axis_name
    self.initial = initial  # e.g. restored from a checkpoint
    self.report = report  # host callback receiving the global state after every batched step

  def initial_stats(self) -> GlobalStats:
    if self.initial is not None:
      return jax.tree_util.tree_map(jnp.asarray, self.initial)
    return GlobalStats(self.core.curriculum.init(), normalizer_init(self.core.cfg.reward))

  def reset(self, rng: jax.Array) -> State:
    return self.reset_with(rng, self.initial_stats())

  def reset_with(self, rng: jax.Array, glob: GlobalStats) -> State:
    """Reset every environment at the difficulty of a given global state (e.g. kept across a
    Gymnasium reset, or restored)."""
    state = self.env.reset(rng)
    n = rng.shape[0]
    fresh = jax.vmap(self.core.reset_at, in_axes=(0, None, None))(rng, glob.curriculum.eps, glob.normalizer.k)
    state = state.replace(pipeline_state=fresh.pipeline_state, obs=fresh.obs)
    state.info["global"] = jax.tree_util.tree_map(lambda x: jnp.broadcast_to(x, (n,) + x.shape), glob)
    state.info["reset_key"] = jax.vmap(lambda k: jax.random.fold_in(k, 7))(rng)
    state.info["final_obs"] = state.obs
    state.info["eps"] = jnp.broadcast_to(glob.curriculum.eps, (n,))
    return state

  def step(self, state: State, action: jax.Array) -> State:
    return self.reset_where_done(*self.step_on(state, action))

  def step_on(self, state: State, action: jax.Array) -> tuple[State, GlobalStats]:
    """step's first part: (the environments after their step, the global state it updated, in
    every environment as in info["global"]); the second (reset_where_done) starts new episodes
    where these ended."""
    if "steps" in state.info:
      state.info["steps"] = jnp.where(state.done, 0, state.info["steps"])
    state = state.replace(done=jnp.zeros_like(state.done))
    nstate = self.env.step(state, action)
    done = nstate.done.astype(bool)
    glob: GlobalStats = jax.tree_util.tree_map(lambda x: x[0], nstate.info["global"])
    ep = nstate.info["episode_metrics"]
    axis = self.axis_name if _axis_bound(self.axis_name) else None
    cur = self.core.curriculum.update(glob.curriculum, done, ep["sum_reward"], ep["progress"], axis)
    penalty_sums = nstate.pipeline_state.penalty_sum
    if axis is not None:
      gather = lambda x: jax.lax.all_gather(x, axis, tiled=True)
      norm = normalizer_update(self.core.cfg.reward, glob.normalizer, gather(done), gather(penalty_sums))
    else:
      norm = normalizer_update(self.core.cfg.reward, glob.normalizer, done, penalty_sums)
    if self.report is not None:
      jax.debug.callback(self.report, GlobalStats(cur, norm))
    n = done.shape[0]
    return nstate, jax.tree_util.tree_map(lambda x: jnp.broadcast_to(x, (n,) + x.shape), GlobalStats(cur, norm))

  def reset_where_done(self, nstate: State, glob: GlobalStats) -> State:
    """step's second part (after step_on): a new episode (scene, spawn, observation) in every
    environment whose episode ended, at the updated curriculum's difficulty."""
    done = nstate.done.astype(bool)
    cur, norm = jax.tree_util.tree_map(lambda x: x[0], (glob.curriculum, glob.normalizer))
    split = jax.vmap(jax.random.split)(nstate.info["reset_key"])

    def where_done(new, old):
      mask = done.reshape(done.shape + (1,) * (new.ndim - done.ndim))
      return jnp.where(mask, new, old)

    def reset_done(_):  # a new episode (scene draw, kinematics, beams) where one ended
      fresh = jax.vmap(self.core.reset_at, in_axes=(0, None, None))(split[:, 0], cur.eps, norm.k)
      return jax.tree_util.tree_map(where_done, (fresh.pipeline_state, fresh.obs), (nstate.pipeline_state, nstate.obs))

    # computed only on steps where some episode ended: a batch of thousands always has one; one
    # robot (the Gymnasium Env) skips the reset's cost on all its other steps
    es, obs = jax.lax.cond(jnp.any(done), reset_done, lambda _: (nstate.pipeline_state, nstate.obs), None)
    es = es.replace(penalty_k=jnp.broadcast_to(norm.k, es.penalty_k.shape))
    n = done.shape[0]
    nstate.info["global"] = glob
    nstate.info["reset_key"] = split[:, 1]
    nstate.info["final_obs"] = nstate.obs
    nstate.info["eps"] = jnp.broadcast_to(cur.eps, (n,))
    return nstate.replace(pipeline_state=es, obs=obs)


def _axis_bound(axis_name: Optional[str]) -> bool:
  """Whether a collective over axis_name is possible here (inside pmap / a named vmap)."""
  if axis_name is None:
    return False
  try:
    jax.lax.axis_index(axis_name)
  except NameError:
    return False
  return True


def wrap_for_training(axis_name: Optional[str] = "i", initial: Optional[GlobalStats] = None,
                      report: Optional[Callable] = None):
  """A `wrap_env_fn` for brax.training.agents.{ppo,sac}.train: Vmap -> Episode -> curriculum reset
  of the TrackedRobotEnv it is given (Brax wraps its training and evaluation envs with it, and
  each keeps its own scenes).

  axis_name is Brax's pmap axis ('i'): where it is bound (training on several devices) the
  curriculum reduces across devices; where it is not (one device, evaluation) it stays local.
  """

  def wrap(env: TrackedRobotEnv, episode_length: int = 1000, action_repeat: int = 1, randomization_fn=None, **_):
    if randomization_fn is not None:
      raise ValueError("mjx_tracks environments randomize their scenes themselves; "
                       "randomization_fn is not supported")
    inner = EpisodeWrapper(VmapWrapper(env), episode_length, action_repeat)
    return CurriculumAutoReset(inner, env, axis_name, initial, report)

  return wrap


def batched_env(core: TrackedRobotEnv, axis_name: Optional[str] = None):
  """The task's batched environment with its own episode length and curriculum reset."""
  return wrap_for_training(axis_name)(core, core.cfg.episode.max_steps, 1)


def global_stats_to_json(g: GlobalStats) -> dict:
  """GlobalStats -> plain lists (for checkpoint metadata; numpy, so that a host state's figures do
  not go to the device and back, two transfers per field and run of a checkpoint round)."""
  plain = lambda obj: {f.name: np.asarray(getattr(obj, f.name)).tolist() for f in dataclasses.fields(obj)}
  return {"curriculum": plain(g.curriculum), "normalizer": plain(g.normalizer)}


def global_stats_from_json(d: dict) -> GlobalStats:
  c, n = d["curriculum"], d["normalizer"]
  return GlobalStats(
      CurriculumState(eps=jnp.float32(c["eps"]), returns=jnp.asarray(c["returns"], jnp.float32),
                      progress=jnp.asarray(c["progress"], jnp.float32), head=jnp.int32(c["head"]),
                      finished=jnp.int32(c["finished"]), updates=jnp.int32(c["updates"])),
      PenaltyNormalizer(k=jnp.float32(n["k"]), total=jnp.float32(n["total"]), count=jnp.int32(n["count"])))

"""Gymnasium interfaces over the same jitted core: one robot (`Env`) and N robots (`VectorEnv`).

Both use the task's batched stack (Vmap -> Episode -> curriculum auto-reset), so the curriculum
runs exactly as in Brax training. The curriculum (eps and its window of finished episodes) lives
across `reset()` calls of one Env or VectorEnv; `info["eps"]` reports it at every reset and step,
`curriculum_state()` returns it and `set_curriculum_state()` restores it. The vector env resets
finished robots in the same step (autoreset mode SAME_STEP; the last observation is in
info["final_obs"]).
"""

from __future__ import annotations

import functools
import sys
import time
from typing import Any, Sequence

import gymnasium as gym
import jax
import jax.numpy as jnp
import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from mjx_tracks import compile_cache
from mjx_tracks.envs.registry import load
from mjx_tracks.envs.wrappers import GlobalStats, batched_env


def _spaces(core) -> tuple[gym.spaces.Box, gym.spaces.Box]:
  obs = gym.spaces.Box(-np.inf, np.inf, (core.observation_size,), np.float32)
  act = gym.spaces.Box(-1.0, 1.0, (core.action_size,), np.float32)
  return obs, act


@functools.lru_cache(maxsize=8)
def _stack(task: str, overrides: tuple[str, ...], n: int) -> "_Stack":
  """One compiled stack per (task, overrides, n): a second Env of the same kind compiles nothing."""
  return _Stack(task, overrides, n)


class _Stack:
  """Jitted reset / step of the batched stack for n robots."""

  def __init__(self, task: str, overrides: Sequence[str], n: int):
    self.core = load(task, overrides)
    self.env = batched_env(self.core)
    self.n = n
    self.reset_with = jax.jit(self.env.reset_with)
    self.step = jax.jit(self.env.step)
    self.initial = self.env.initial_stats()
    self._compile(task)

  def _compile(self, task: str) -> None:
    """Compiles reset and step now, saying so (the first time on a machine: a minute or more,
    which a first reset() would otherwise spend in silence); uses the persistent compilation
    cache unless the caller set up JAX's own."""
    if jax.config.jax_compilation_cache_dir is None:
      compile_cache.enable()
    print(f"mjx-tracks: compiling {task} for {self.n} robot(s) (a minute or more the first time on this machine; "
          f"cached in {jax.config.jax_compilation_cache_dir}) ...", file=sys.stderr, flush=True)
    t0 = time.time()
    state = self.reset(0, self.initial)
    jax.block_until_ready(self.step(state, jnp.zeros((self.n, self.core.action_size), jnp.float32)))
    print(f"mjx-tracks: compiled in {time.time() - t0:,.0f} s", file=sys.stderr, flush=True)

  def reset(self, seed: int, glob: GlobalStats):
    return self.reset_with(jax.random.split(jax.random.PRNGKey(seed), self.n), glob)

  @staticmethod
  def global_stats(state) -> GlobalStats:
    """The curriculum and penalty-normalizer state (identical in every environment)."""
    return jax.tree_util.tree_map(lambda x: x[0], state.info["global"])

  @staticmethod
  def outputs(s) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict]:
    """(obs, reward, terminated, truncated, info) on the host, fetched in one transfer (a transfer
    per array would cost a third of a one-robot step on the CPU)."""
    obs, reward, done, trunc, final, eps, metrics = jax.device_get(
        (s.obs, s.reward, s.done, s.info["truncation"], s.info["final_obs"], s.info["eps"], s.metrics))
    done = np.asarray(done, bool)
    trunc = np.asarray(trunc, bool) & done
    info = {"eps": np.asarray(eps), "final_obs": np.asarray(final, np.float32), **metrics}
    return np.asarray(obs, np.float32), np.asarray(reward, np.float64), done & ~trunc, trunc, info


def _frame(core, state, index: int, width: int, height: int) -> np.ndarray:
  from mjx_tracks.tools.render import render_frames  # noqa: PLC0415
  es = jax.tree_util.tree_map(lambda x: np.asarray(x[index]), state.pipeline_state)
  mj = core.sim.c_model_with_boxes(es.scene.box_pos, es.scene.box_size, es.scene.box_yaw)
  return render_frames(mj, es.data.qpos[None], width, height)[0]


class _KeepsCurriculum:
  """The curriculum of a Gymnasium env lives across its resets; it can be read and restored."""

  def curriculum_state(self) -> GlobalStats:
    """The curriculum (and penalty normalizer) state, kept across resets."""
    return self._glob if self._state is None else self._stack.global_stats(self._state)

  def set_curriculum_state(self, glob: GlobalStats) -> None:
    """Restores a state from curriculum_state(); the next reset draws at its eps."""
    self._glob, self._state = glob, None


class TrackedRobotGymEnv(_KeepsCurriculum, gym.Env):
  """One robot of a task, with proper spaces, seeding, terminated / truncated and rgb rendering."""

  metadata = {"render_modes": ["rgb_array"], "render_fps": 4}

  def __init__(self, task: str, overrides: Sequence[str] = (), render_mode: str | None = None,
               render_size: tuple[int, int] = (320, 240)):
    if render_mode not in (None, "rgb_array"):
      raise ValueError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
    self._stack = _stack(task, tuple(overrides), 1)
    self.observation_space, self.action_space = _spaces(self._stack.core)
    self.render_mode = render_mode
    self._size = render_size
    self._state = None
    self._glob = self._stack.initial
    self.metadata = dict(self.metadata, render_fps=int(round(1 / self._stack.core.cfg.control.period)))

  def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
    super().reset(seed=seed)
    self._glob = self.curriculum_state()
    self._state = self._stack.reset(int(self.np_random.integers(2**31)), self._glob)
    return np.asarray(self._state.obs[0], np.float32), {"eps": float(self._state.info["eps"][0])}

  def step(self, action):
    if self._state is None:
      raise RuntimeError("call reset() before step()")
    self._state = self._stack.step(self._state, np.asarray(action, np.float32).reshape(1, -1))
    _, reward, term, trunc, out = self._stack.outputs(self._state)
    info = {k: float(v[0]) for k, v in out.items() if k != "final_obs"}
    return out["final_obs"][0], float(reward[0]), bool(term[0]), bool(trunc[0]), info

  def render(self):
    if self.render_mode != "rgb_array" or self._state is None:
      return None
    return _frame(self._stack.core, self._state, 0, *self._size)


class TrackedRobotVectorEnv(_KeepsCurriculum, VectorEnv):
  """N robots of a task stepped by one jitted batch call."""

  metadata = {"render_modes": ["rgb_array"], "autoreset_mode": AutoresetMode.SAME_STEP}

  def __init__(self, task: str, num_envs: int, overrides: Sequence[str] = (),
               render_mode: str | None = None, render_size: tuple[int, int] = (320, 240)):
    if num_envs < 1:
      raise ValueError("num_envs must be >= 1")
    self._stack = _stack(task, tuple(overrides), num_envs)
    self.num_envs = num_envs
    self.single_observation_space, self.single_action_space = _spaces(self._stack.core)
    self.observation_space = batch_space(self.single_observation_space, num_envs)
    self.action_space = batch_space(self.single_action_space, num_envs)
    self.render_mode = render_mode
    self._size = render_size
    self._state = None
    self._glob = self._stack.initial

  def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
    if seed is not None:
      self._np_random, self._np_random_seed = gym.utils.seeding.np_random(seed)
    self._glob = self.curriculum_state()
    self._state = self._stack.reset(int(self.np_random.integers(2**31)), self._glob)
    return np.asarray(self._state.obs, np.float32), {"eps": np.asarray(self._state.info["eps"])}

  def step(self, actions):
    if self._state is None:
      raise RuntimeError("call reset() before step()")
    self._state = self._stack.step(self._state, np.asarray(actions, np.float32))
    obs, reward, term, trunc, info = self._stack.outputs(self._state)
    return obs, reward, term, trunc, {**info, "_final_obs": term | trunc}

  def render(self):
    if self.render_mode != "rgb_array" or self._state is None:
      return None
    return _frame(self._stack.core, self._state, 0, *self._size)

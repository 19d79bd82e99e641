"""The task's Gymnasium VectorEnv as a Stable-Baselines3 VecEnv, with each finished episode's sums.

SB3 steps its own VecEnv type; this adapter serves it N robots of one jitted batch
(mjx_tracks.envs.gym_env.TrackedRobotVectorEnv) instead of N Python envs. It follows SB3's VecEnv
contract: finished robots reset in the same step, their last observation in
infos[i]["terminal_observation"], a time limit flagged as infos[i]["TimeLimit.truncated"], and the
episode's return and length in infos[i]["episode"] (what SB3's Monitor writes, so SB3's own
rollout/ep_rew_mean logging works). Beside that it sums every per-step metric of
mjx_tracks.metrics.STEP over each episode and keeps the finished episodes' sums until `take_finished`
collects them: the same figures (one metrics schema) as the project's trainer reports.
"""

from __future__ import annotations

import time
from typing import Any, Sequence

import numpy as np

import train.core.no_triton  # noqa: F401  (before PyTorch loads)
from stable_baselines3.common.vec_env.base_vec_env import VecEnv  # noqa: E402

from mjx_tracks.envs.gym_env import TrackedRobotVectorEnv
from mjx_tracks.metrics import STEP_NAMES


class TaskVecEnv(VecEnv):
  """N robots of a task for SB3; `curriculum_state` / `set_curriculum_state` pass through."""

  def __init__(self, task: str, num_envs: int, overrides: Sequence[str] = (), seed: int = 0):
    self.env = TrackedRobotVectorEnv(task, num_envs, overrides)
    self.render_mode = None  # SB3's VecEnv asks for it
    super().__init__(num_envs, self.env.single_observation_space, self.env.single_action_space)
    self._seed = seed
    self._actions = None
    self._sums = np.zeros((num_envs, len(STEP_NAMES)), np.float64)
    self._returns = np.zeros(num_envs, np.float64)
    self._lengths = np.zeros(num_envs, np.int64)
    self._finished: list[dict[str, float]] = []
    self._t0 = time.time()
    self.eps = 0.0  # the curriculum's difficulty at the last step

  def reset(self):
    obs, info = self.env.reset(seed=self._seed)
    self._seed += 1  # a later reset (SB3 calls one per learn()) draws other scenes
    self._sums[:], self._returns[:], self._lengths[:] = 0.0, 0.0, 0
    self.eps = float(np.asarray(info["eps"])[0])
    return obs

  def step_async(self, actions: np.ndarray) -> None:
    self._actions = actions

  def step_wait(self):
    obs, reward, term, trunc, info = self.env.step(self._actions)
    done = term | trunc
    self._sums += np.stack([np.asarray(info[k], np.float64) for k in STEP_NAMES], axis=1)
    self._returns += reward
    self._lengths += 1
    self.eps = float(np.asarray(info["eps"])[0])
    infos: list[dict[str, Any]] = [{} for _ in range(self.num_envs)]
    for i in np.flatnonzero(done):
      episode = {"r": float(self._returns[i]), "l": int(self._lengths[i]), "t": time.time() - self._t0}
      infos[i] = {"terminal_observation": info["final_obs"][i], "TimeLimit.truncated": bool(trunc[i] and not term[i]),
                  "episode": episode}
      self._finished.append({**dict(zip(STEP_NAMES, self._sums[i])), "sum_reward": episode["r"], "length": episode["l"]})
      self._sums[i], self._returns[i], self._lengths[i] = 0.0, 0.0, 0
    return obs, reward.astype(np.float32), done, infos

  def take_finished(self) -> list[dict[str, float]]:
    """The sums of the episodes finished since the last call (STEP metrics, sum_reward, length)."""
    out, self._finished = self._finished, []
    return out

  def curriculum_state(self):
    return self.env.curriculum_state()

  def set_curriculum_state(self, glob) -> None:
    self.env.set_curriculum_state(glob)

  def close(self) -> None:
    pass

  def get_attr(self, attr_name: str, indices=None) -> list[Any]:
    return [getattr(self, attr_name)] * len(self._indices(indices))

  def set_attr(self, attr_name: str, value: Any, indices=None) -> None:
    setattr(self, attr_name, value)

  def env_method(self, method_name: str, *args, indices=None, **kwargs) -> list[Any]:
    return [getattr(self, method_name)(*args, **kwargs)] * len(self._indices(indices))

  def env_is_wrapped(self, wrapper_class, indices=None) -> list[bool]:
    return [False] * len(self._indices(indices))

  def seed(self, seed: int | None = None):
    if seed is not None:
      self._seed = seed
    return [self._seed] * self.num_envs

  def _indices(self, indices) -> list[int]:
    if indices is None:
      return list(range(self.num_envs))
    return [indices] if isinstance(indices, int) else list(indices)


def episode_metrics(finished: list[dict[str, float]]) -> dict[str, float]:
  """Brax-style 'episode/...' means of finished episodes' sums: what train.core.progress.summarize
  reads (so an SB3 run's reports are the project's trainer's columns)."""
  if not finished:
    return {}
  keys = finished[0].keys()
  return {f"episode/{k}": float(np.mean([e[k] for e in finished])) for k in keys}

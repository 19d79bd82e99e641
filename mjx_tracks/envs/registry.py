"""Task registry: a task is a YAML file in configs/; `load` builds its Brax environment."""

from __future__ import annotations

from typing import Sequence

from mjx_tracks.envs.config import available_tasks, load_config
from mjx_tracks.envs.task_env import TrackedRobotEnv


def load(task: str, overrides: Sequence[str] = ()) -> TrackedRobotEnv:
  """The Brax env of `task` (configs/<task>.yaml with dotted KEY=VALUE overrides)."""
  return TrackedRobotEnv(load_config(task, overrides))


__all__ = ["available_tasks", "load", "load_config"]

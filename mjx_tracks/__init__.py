"""mjx-tracks: vectorised RL for articulated tracked robots on MuJoCo MJX.

After `import mjx_tracks`, every task in configs/ is registered with Gymnasium as
`mjx_tracks/<task>-v0` (single robot and vector env), and `mjx_tracks.load(task, overrides)`
returns the task's Brax environment.
"""

import ctypes.util
import os

# Offscreen rendering needs its GL backend chosen before mujoco is first imported: EGL where
# the machine has it and no display (a GPU host without libEGL keeps mujoco's default).
if "MUJOCO_GL" not in os.environ and not os.environ.get("DISPLAY") and ctypes.util.find_library("EGL"):
  os.environ["MUJOCO_GL"] = "egl"

from mjx_tracks import quiet_mjx  # noqa: E402


quiet_mjx.install()  # mujoco.mjx, whoever imports it first, without the Warp lines


def load(task: str, overrides=()):
  """The Brax environment of a task (configs/<task>.yaml plus dotted KEY=VALUE overrides)."""
  from mjx_tracks.envs.registry import load as _load  # noqa: PLC0415
  return _load(task, overrides)


def _register_gymnasium() -> None:
  import gymnasium  # noqa: PLC0415

  from mjx_tracks.envs.task_files import available_tasks  # noqa: PLC0415  (no JAX: a light import)
  for task in available_tasks():
    env_id = f"mjx_tracks/{task}-v0"
    if env_id not in gymnasium.registry:
      gymnasium.register(id=env_id, entry_point="mjx_tracks.envs.gym_env:TrackedRobotGymEnv",
                         vector_entry_point="mjx_tracks.envs.gym_env:TrackedRobotVectorEnv",
                         kwargs={"task": task})


_register_gymnasium()

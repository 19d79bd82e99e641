"""Offscreen rendering of recorded trajectories to RGB frames and MP4 (CPU, EGL)."""

from __future__ import annotations

import mujoco
import numpy as np


FOLLOW = {"distance": 3.0, "elevation": -20.0}  # m, deg: behind and beside the robot (stairs, terrains)
OVERHEAD = {"distance": 9.0, "elevation": -65.0}  # m, deg: high above it, over the walls (navigation areas)


CAMERAS = {"follow": FOLLOW, "overhead": OVERHEAD}  # a scene kind's `camera` (scenes.kinds) -> its settings


def camera_for(camera: str) -> dict:
  """The following camera's distance and elevation: a scene kind's camera, "follow" or "overhead"."""
  return CAMERAS[camera]


def render_frames(mj_model, qpos_seq: np.ndarray, width: int = 480, height: int = 360,
                  distance: float = FOLLOW["distance"], elevation: float = FOLLOW["elevation"]) -> list[np.ndarray]:
  """One RGB frame per qpos row, from a camera that follows the chassis (distance m, elevation deg)."""
  data = mujoco.MjData(mj_model)
  cam = mujoco.MjvCamera()
  cam.distance, cam.azimuth, cam.elevation = distance, 120.0, elevation
  frames = []
  with mujoco.Renderer(mj_model, height, width) as renderer:
    for q in qpos_seq:
      data.qpos[:] = q
      mujoco.mj_forward(mj_model, data)
      cam.lookat[:] = data.qpos[:3]
      renderer.update_scene(data, camera=cam)
      frames.append(renderer.render().copy())
  return frames


def write_video(path: str, frames: list[np.ndarray], fps: float) -> None:
  """Writes frames to a GIF (a path ending .gif; at half size, Pillow) or an MP4 (needs the `video`
  extra: imageio + imageio-ffmpeg)."""
  if path.lower().endswith(".gif"):
    write_gif(path, frames, fps)
    return
  try:
    import imageio.v2 as imageio  # noqa: PLC0415
  except ImportError as e:
    raise SystemExit("error: --video needs the video extra: pip install 'mjx-tracks[video]'") from e
  imageio.mimwrite(path, frames, fps=fps, macro_block_size=1)


def write_gif(path: str, frames: list[np.ndarray], fps: float) -> None:
  """Writes frames, halved in each dimension, to a looping GIF (Pillow, a matplotlib dependency)."""
  from PIL import Image  # noqa: PLC0415
  images = [Image.fromarray(np.ascontiguousarray(f[::2, ::2])) for f in frames]
  images[0].save(path, save_all=True, append_images=images[1:], duration=round(1000 / fps), loop=0, optimize=True)


def render_depth(mj_model, qpos: np.ndarray, camera: str = "depth_camera") -> np.ndarray:
  """The robot's real depth image (m, z-depth) at its camera resolution, for notebooks / debugging."""
  data = mujoco.MjData(mj_model)
  data.qpos[:] = qpos
  mujoco.mj_forward(mj_model, data)
  w, h = mj_model.vis.global_.offwidth, mj_model.vis.global_.offheight
  with mujoco.Renderer(mj_model, h, w) as renderer:
    renderer.enable_depth_rendering()
    renderer.update_scene(data, camera=camera)
    return renderer.render().copy()

"""Real depth image against ray casting; GIFs of rendered frames; keyboard teleop key mapping."""

import mujoco
import numpy as np
import pytest

from mjx_tracks.robots import get_robot
from mjx_tracks.sim.control import INCREMENT
from mjx_tracks.tools.render import render_depth, render_frames, write_video
from mjx_tracks.tools.teleop import apply_key


def test_depth_image_centre_matches_a_ray_along_the_camera_axis(jaguar_stairs):
  sim = jaguar_stairs
  n = len(sim.layout.scene_boxes)
  pos, size = np.tile([-50.0, 0, -10], (n, 1)), np.full((n, 3), 0.1)
  pos[0], size[0] = (1.5, 0, 0.5), (0.5, 1.0, 0.5)  # a block ahead, the rest parked
  mj = sim.c_model_with_boxes(pos, size)
  assert mj is not sim.mj_model and sim.mj_model.geom_pos[sim.layout.scene_boxes[0], 2] < -5
  qpos = mj.qpos0.copy()
  qpos[2] = sim.robot.spawn_height
  depth = render_depth(mj, qpos)
  assert depth.shape == (480, 640)
  data = mujoco.MjData(mj)
  data.qpos[:] = qpos
  mujoco.mj_forward(mj, data)
  cam = sim.layout.camera_site
  axis = -data.site_xmat[cam].reshape(3, 3)[:, 2]  # the camera looks along its -z
  oracle = mujoco.mj_ray(mj, data, data.site_xpos[cam], axis, np.array([1, 0, 0, 0, 0, 0], np.uint8),
                         1, -1, np.zeros(1, np.int32))
  centre = depth[239:241, 319:321].mean()
  assert oracle > 0 and centre == pytest.approx(oracle, abs=0.01)


def test_a_gif_holds_every_rendered_frame_at_half_size_and_the_control_rate(jaguar_stairs, tmp_path):
  from PIL import Image
  sim = jaguar_stairs
  n = len(sim.layout.scene_boxes)
  pos, size, yaw = np.tile([-50.0, 0, -10], (n, 1)), np.full((n, 3), 0.1), np.zeros(n)
  pos[0], size[0], yaw[0] = (1.5, 0, 0.2), (0.5, 1.0, 0.2), 0.6  # a yawed block ahead
  mj = sim.c_model_with_boxes(pos, size, yaw)
  qpos = np.tile(mj.qpos0, (3, 1))
  qpos[:, 0] = [0.0, 0.1, 0.2]
  frames = render_frames(mj, qpos, width=160, height=120)
  write_video(str(tmp_path / "t.gif"), frames, fps=4.0)
  with Image.open(tmp_path / "t.gif") as gif:
    assert (gif.n_frames, gif.size, gif.info["duration"], gif.info["loop"]) == (3, (80, 60), 250, 0)
    first = np.asarray(gif.convert("RGB"), float)
  assert np.abs(first - frames[0][::2, ::2]).mean() < 8  # palette quantization only


def test_keys_drive_speeds_and_clip_joint_targets():
  robot = get_robot(1)
  lim = robot.flipper_limit
  v, w, t, quit_ = apply_key("w", 0.0, 0.0, np.zeros(6), robot)
  assert (v, w, quit_) == (pytest.approx(0.1), 0.0, False)
  v, w, t, _ = apply_key("a", v, w, t, robot)
  assert w == pytest.approx(0.2)
  for _ in range(20):
    v, w, t, _ = apply_key("i", v, w, t, robot)
  np.testing.assert_allclose(t[robot.joint_index("front")], lim)  # front pair raised, clipped at the limit
  np.testing.assert_allclose(t[robot.joint_index("rear")], 0.0)
  v, w, t, _ = apply_key("o", v, w, t, robot)
  np.testing.assert_allclose(t[robot.joint_index("rear")], INCREMENT / 2)
  v, w, t, _ = apply_key("y", v, w, t, robot)
  np.testing.assert_allclose(t[robot.joint_index("arm_2")], INCREMENT / 2)
  v, w, _, _ = apply_key(" ", v, w, t, robot)
  assert (v, w) == (0.0, 0.0)
  assert apply_key("q", v, w, t, robot)[3]
  t2 = apply_key("u", 0.0, 0.0, np.zeros(4), get_robot(2))[2]  # no arm: arm keys change nothing
  np.testing.assert_array_equal(t2, 0.0)

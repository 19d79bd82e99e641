"""Keyboard teleoperation in the terminal (the original's keyboard teleop), stepped in real time."""

from __future__ import annotations

import contextlib
import select
import sys
import termios
import time
import tty

import jax
import jax.numpy as jnp
import numpy as np

from mjx_tracks.robots.spec import RobotSpec
from mjx_tracks.sim.control import INCREMENT, command_belt_speeds

HELP = ("keys: w/s speed +-0.1 m/s, a/d yaw rate +-0.2 rad/s, space stop, "
        "i/k front flippers up/down, o/l rear flippers up/down, u/j arm 1, y/h arm 2, q quit")

# key -> (joint group, sign)
_JOINT_KEYS = {"i": ("front", 1), "k": ("front", -1), "o": ("rear", 1), "l": ("rear", -1),
               "u": ("arm_1", 1), "j": ("arm_1", -1), "y": ("arm_2", 1), "h": ("arm_2", -1)}


def apply_key(key: str, v: float, w: float, targets: np.ndarray, robot: RobotSpec
              ) -> tuple[float, float, np.ndarray, bool]:
  """One key press -> new (v m/s, w rad/s, joint targets rad, quit?)."""
  targets = targets.copy()
  if key == "w":
    v = min(v + 0.1, robot.max_speed)
  elif key == "s":
    v = max(v - 0.1, -robot.max_speed)
  elif key == "a":
    w += 0.2
  elif key == "d":
    w -= 0.2
  elif key == " ":
    v, w = 0.0, 0.0
  elif key in _JOINT_KEYS:
    group, sign = _JOINT_KEYS[key]
    limits = robot.joint_limits()
    for j in robot.joint_index(group):
      targets[j] = np.clip(targets[j] + sign * INCREMENT / 2, limits[j, 0], limits[j, 1])
  return v, w, targets, key == "q"


@contextlib.contextmanager
def _raw_terminal():
  fd = sys.stdin.fileno()
  old = termios.tcgetattr(fd)
  try:
    tty.setcbreak(fd)
    yield
  finally:
    termios.tcsetattr(fd, termios.TCSADRAIN, old)


def keyboard_rollout(setup, n_steps: int) -> np.ndarray:
  """Drives with the keyboard for up to n_steps control periods; returns qpos per step."""
  if not sys.stdin.isatty():
    raise SystemExit("error: --controller keyboard needs an interactive terminal")
  sim, robot = setup.sim, setup.sim.robot
  m = setup.model()
  step = jax.jit(lambda d, belts, tgt: sim.advance(m, d, belts, tgt, setup.substeps))
  d = setup.initial_data()
  v, w, targets = 0.0, 0.0, np.zeros(sim.layout.n_joints, np.float32)
  print(HELP, file=sys.stderr)
  qpos = [np.asarray(d.qpos)]
  with _raw_terminal():
    for _ in range(n_steps):
      t0 = time.time()
      while select.select([sys.stdin], [], [], 0)[0]:
        v, w, targets, quit_ = apply_key(sys.stdin.read(1), v, w, targets, robot)
        if quit_:
          return np.stack(qpos)
      belts = command_belt_speeds(v, w, robot.track_separation, robot.steering_efficiency,
                                  robot.max_speed)
      d = step(d, belts, jnp.asarray(targets))
      qpos.append(np.asarray(d.qpos))
      print(f"\rv={v:+.1f} w={w:+.1f} x={float(d.qpos[0]):+.2f} z={float(d.qpos[2]):.2f}   ",
            end="", file=sys.stderr)
      time.sleep(max(0.0, setup.control_period - (time.time() - t0)))
  print(file=sys.stderr)
  return np.stack(qpos)

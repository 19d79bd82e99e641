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

from mjx_tracks.control import INCREMENT, command_belt_speeds

HELP = ("keys: w/s speed +-0.1 m/s, a/d yaw rate +-0.2 rad/s, space stop, "
        "i/k front flippers up/down, o/l rear flippers up/down, u/j arm 1, y/h arm 2, q quit")

# key -> (joint indices, sign); joints: fl, fr, rl, rr, arm_1, arm_2
_JOINT_KEYS = {"i": ((0, 1), 1), "k": ((0, 1), -1), "o": ((2, 3), 1), "l": ((2, 3), -1),
               "u": ((4,), 1), "j": ((4,), -1), "y": ((5,), 1), "h": ((5,), -1)}


def apply_key(key: str, v: float, w: float, targets: np.ndarray, limits: np.ndarray,
              max_speed: float) -> tuple[float, float, np.ndarray, bool]:
  """One key press -> new (v m/s, w rad/s, joint targets rad, quit?)."""
  targets = targets.copy()
  if key == "w":
    v = min(v + 0.1, max_speed)
  elif key == "s":
    v = max(v - 0.1, -max_speed)
  elif key == "a":
    w += 0.2
  elif key == "d":
    w -= 0.2
  elif key == " ":
    v, w = 0.0, 0.0
  elif key in _JOINT_KEYS:
    joints, sign = _JOINT_KEYS[key]
    for j in joints:
      if j < len(targets):
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
  limits = sim.layout.joint_limits
  v, w, targets = 0.0, 0.0, np.zeros(sim.layout.n_joints, np.float32)
  print(HELP, file=sys.stderr)
  qpos = [np.asarray(d.qpos)]
  with _raw_terminal():
    for _ in range(n_steps):
      t0 = time.time()
      while select.select([sys.stdin], [], [], 0)[0]:
        v, w, targets, quit_ = apply_key(sys.stdin.read(1), v, w, targets, limits, robot.max_speed)
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

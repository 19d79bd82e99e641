"""Low-level control: action decoding, clipping, increments, skid-steer belt speeds."""

import math

import jax.numpy as jnp
import numpy as np
import pytest

from mjx_tracks.sim.control import CONTROL_MODES, INCREMENT, Controller, command_belt_speeds
from mjx_tracks.robots import get_robot

JAGUAR, ABSOLEM = get_robot(1), get_robot(2)


def test_modes_have_their_sizes():  # the paper's four, and 3dof_stairs for robot 2 on stairs
  assert {k: len(v) for k, v in CONTROL_MODES.items()} == {
      "4dof": 4, "6dof": 6, "8dof": 8, "5dof_stairs": 5, "3dof_stairs": 3}


def test_the_armless_stair_mode_drives_robot_2s_flipper_pairs():
  c = Controller.create(ABSOLEM, "3dof_stairs", increments=True)
  v, w, t = c.decode(jnp.array([1.0, 1.0, -0.5]), jnp.zeros(4))
  front, rear = ABSOLEM.joint_index("front"), ABSOLEM.joint_index("rear")
  assert float(v) == pytest.approx(1.0) and float(w) == 0.0 and len(front) == len(rear) == 2
  np.testing.assert_allclose(np.asarray(t)[front], INCREMENT, atol=1e-6)
  np.testing.assert_allclose(np.asarray(t)[rear], -0.5 * INCREMENT, atol=1e-6)


def test_stair_mode_increments_accumulate_and_clip():
  c = Controller.create(JAGUAR, "5dof_stairs", increments=True)
  prev = jnp.zeros(6)
  v, w, t = c.decode(jnp.array([1.0, 1.0, -1.0, 0.5, 0.0]), prev)
  assert float(v) == pytest.approx(1.0) and float(w) == 0.0
  np.testing.assert_allclose(t, [INCREMENT, INCREMENT, -INCREMENT, -INCREMENT, 0.5 * INCREMENT, 0],
                             atol=1e-6)
  for _ in range(5):
    _, _, t = c.decode(jnp.array([0.0, 1.0, -1.0, 1.0, 0.0]), t)
  lim = JAGUAR.flipper_limit
  np.testing.assert_allclose(t[:4], [lim, lim, -lim, -lim], atol=1e-6)
  assert float(t[4]) <= JAGUAR.arm.joint1_limit


def test_absolute_targets_span_the_limits():
  c = Controller.create(JAGUAR, "8dof", increments=False, v_range=(-1.0, 1.0))
  _, _, t = c.decode(jnp.array([0, 0, 1, -1, 0, 0, 1, -1.0]), jnp.zeros(6))
  np.testing.assert_allclose(t, [math.pi / 4, -math.pi / 4, 0, 0, 1.3, -2.9], atol=1e-5)


def test_nan_and_out_of_range_actions_are_clipped_not_propagated():
  c = Controller.create(JAGUAR, "6dof", increments=True)
  v, w, t = c.decode(jnp.array([jnp.nan, 50.0, jnp.inf, -jnp.inf, jnp.nan, 3.0]), jnp.zeros(6))
  assert np.isfinite([float(v), float(w)]).all() and np.isfinite(np.asarray(t)).all()
  assert float(v) == pytest.approx(0.5)  # NaN -> 0 -> middle of [0, 1] m/s
  assert float(w) == pytest.approx(JAGUAR.max_yaw_rate)
  np.testing.assert_allclose(t[:4], [0.0, 0.0, 0.0, INCREMENT], atol=1e-6)  # +-inf and NaN -> 0
  assert command_belt_speeds(jnp.nan, 0.3, 0.6, 0.5, 1.0).tolist() == pytest.approx([-0.18, 0.18] * 3)


def test_belt_speeds_follow_skid_steer_and_clip():
  u = np.asarray(command_belt_speeds(0.2, 0.5, 0.6, 0.5, 1.0))
  np.testing.assert_allclose(u, [0.2 - 0.3, 0.5, -0.1, 0.5, -0.1, 0.5], atol=1e-6)
  u = np.asarray(command_belt_speeds(0.9, 1.0, 0.6, 0.5, 1.0))
  assert u.max() == pytest.approx(1.0)


def test_bad_modes_fail_clearly():
  with pytest.raises(ValueError, match="unknown control mode"):
    Controller.create(JAGUAR, "3dof")
  with pytest.raises(ValueError, match="has none"):
    Controller.create(ABSOLEM, "5dof_stairs")
  with pytest.raises(ValueError, match="v_range"):
    Controller.create(JAGUAR, "4dof", v_range=(0.0, 3.0))


DOF = (("front", 0.3), ("rear", 0.3), ("arm_1", 0.6), ("arm_2", 0.6))  # flippers, then the arm


@pytest.mark.parametrize("increments", [True, False])
def test_the_dof_curriculum_holds_locked_joints_at_their_targets_until_eps_reaches_them(increments):
  staged = Controller.create(JAGUAR, "5dof_stairs", increments, dof_curriculum=DOF)
  free = Controller.create(JAGUAR, "5dof_stairs", increments)
  prev = jnp.array([0.1, 0.1, -0.2, -0.2, 0.3, -0.4])  # front l/r, rear l/r, arm 1/2 (rad)
  action = jnp.array([0.2, 0.5, -0.7, 0.9, -0.3])  # v, front, rear, arm_1, arm_2
  _, _, moved = free.decode(action, prev)
  flippers, arm = slice(0, 4), slice(4, 6)
  assert not np.allclose(moved[flippers], prev[flippers]) and not np.allclose(moved[arm], prev[arm])
  for eps, acting in ((0.0, ()), (0.29, ()), (0.3, (flippers,)), (0.59, (flippers,)), (0.6, (flippers, arm)),
                      (1.0, (flippers, arm))):
    v, w, t = staged.decode(action, prev, jnp.float32(eps))
    assert float(v) == pytest.approx(0.6) and float(w) == 0.0  # v always acts
    expected = np.asarray(prev).copy()
    for part in acting:
      expected[part] = np.asarray(moved)[part]
    np.testing.assert_allclose(t, expected, atol=1e-6, err_msg=f"eps {eps}")


@pytest.mark.parametrize("mode, increments", [("5dof_stairs", True), ("5dof_stairs", False), ("4dof", True),
                                              ("3dof_stairs", True)])
def test_encode_is_decodes_inverse_for_reachable_commands(mode, increments):
  """A scripted controller's (v, w, targets) through encode then decode come back (within one step's
  increment); farther targets are approached by a full increment."""
  robot = ABSOLEM if mode == "3dof_stairs" else JAGUAR
  c = Controller.create(robot, mode, increments=increments)
  prev = jnp.asarray(np.linspace(-0.2, 0.2, len(robot.joint_names())), jnp.float32)
  near = prev + 0.5 * INCREMENT * jnp.sign(jnp.arange(len(prev)) % 2 - 0.5)
  for group in ("front", "rear", "arm_1", "arm_2"):  # a group's joints share a target
    idx = robot.joint_index(group)
    if len(idx):
      near = near.at[idx].set(near[idx[0]])
      prev = prev.at[idx].set(prev[idx[0]])
  driven = np.asarray(c.drive).sum(axis=1) > 0
  v, w, t = c.decode(c.encode(jnp.float32(0.3), jnp.float32(0.2), near, prev), prev)
  assert float(v) == pytest.approx(0.3, abs=1e-6)
  assert float(w) == pytest.approx(0.2 if "w" in c.dims else 0.0, abs=1e-6)
  np.testing.assert_allclose(np.asarray(t)[driven], np.asarray(near)[driven], atol=1e-5)
  if increments:  # a target two increments away: one full increment toward it
    _, _, t = c.decode(c.encode(jnp.float32(0.3), jnp.float32(0.0), prev + 2 * INCREMENT, prev), prev)
    np.testing.assert_allclose(np.asarray(t)[driven], np.minimum(np.asarray(prev + INCREMENT), np.asarray(c.joint_limits[:, 1]))[driven], atol=1e-5)

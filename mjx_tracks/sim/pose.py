"""Chassis pose: position, roll / pitch / yaw, nose-up angle, from MJX data."""

from __future__ import annotations

import jax
import jax.numpy as jnp


def wrap_angle(a: jax.Array) -> jax.Array:
  """An angle (rad) mapped onto [-pi, pi)."""
  return (a + jnp.pi) % (2 * jnp.pi) - jnp.pi


def quat_to_rpy(q: jax.Array) -> jax.Array:
  """(w, x, y, z) quaternion -> (roll, pitch, yaw) rad, ZYX convention (pitch > 0: nose down)."""
  w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
  roll = jnp.arctan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
  pitch = jnp.arcsin(jnp.clip(2 * (w * y - z * x), -1.0, 1.0))
  yaw = jnp.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
  return jnp.stack([roll, pitch, yaw], axis=-1)


def chassis_rpy(qpos: jax.Array) -> jax.Array:
  """Roll, pitch, yaw of the free-floating chassis (rad) from qpos."""
  return quat_to_rpy(qpos[..., 3:7])


def chassis_velocity(rot: jax.Array, qvel: jax.Array) -> jax.Array:
  """(3,) m/s: the chassis's linear velocity in its own frame (x forward, y left, z up), from its
  rotation matrix (3, 3: d.xmat of its body) and qvel (the free joint's first three: world frame)."""
  return rot.T @ qvel[0:3]


def tipped_over(rpy: jax.Array) -> jax.Array:
  """True when |roll| or |pitch| exceeds pi/2 (the reference's tip-over rule)."""
  return (jnp.abs(rpy[..., 0]) > jnp.pi / 2) | (jnp.abs(rpy[..., 1]) > jnp.pi / 2)

"""Track-contact model: Contact Surface Motion (CSM) inside MJX's constraint solver.

MJX has no belt surface velocity. After collision and before the solver, for every contact that
touches a belt geom (a capsule whose axis segment carries the belt):

1. the contact frame is turned so its first tangent runs along the belt and the friction
   coefficients become (mu_along, mu_across): anisotropic belt friction;
2. the reference acceleration of the contact's friction rows is shifted so that the solver drives
   the tangential slip toward the belt's surface velocity instead of toward zero.

Belt surface velocity at a contact point p (belt speed u, lateral axis y of the belt's body,
radial direction r from the capsule's axis segment to p):  u_vec = u * (y x r). On the flat
bottom it points backward (the robot moves forward for u > 0); on the rounded ends it runs up or
down, which carries the belt over stair edges.

Pyramidal friction rows of a condim-3 contact are J_n +- mu_i J_ti with
aref = -b (J qvel) - k imp pos. Adding +-b mu_i s_i makes the solver target tangential slip
s_i = t_i . (v2 - v1) instead of 0, where v2 - v1 = +u_vec if the belt is geom 1 of the pair and
-u_vec if it is geom 2.

Steering efficiency e (fraction of the differential belt speed that turns the robot): a contact at
lateral offset y_c from the chassis centre is driven along the belt at
v_bar + e * (u_b - v_bar) * |y_c| / (S/2), with v_bar the mean of the two side tracks' speeds and
S the track separation, and across the belt at the skid velocity Omega * x_c of the turn
(x_c its longitudinal offset). The targets of all contacts are then those of one rigid motion
with forward speed v_bar and yaw rate Omega = e * (u_right - u_left) / S, the reference's
steering-efficiency relation; friction acts on deviations from it. Without the skid term,
lateral sliding would use up the friction pyramid and the robot would turn at ~70 % of Omega.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import mujoco
import numpy as np

from mjx_tracks.sim import mjx_private
from mjx_tracks.sim.layout import BELT_SIDE, Layout


@dataclasses.dataclass(frozen=True)
class TrackModel:
  """Static figures of the belts of one model (numpy, resolved once)."""

  geom_belt: np.ndarray  # (ngeom,) belt index or -1
  belt_side: np.ndarray  # (n_belts,) +1 left, -1 right
  chassis_body: int
  mu_along: float
  mu_across: float
  track_separation: float  # m
  steering_efficiency: float
  contact_row0: int  # first efc row of the contacts (all contacts condim 3, 4 rows each)

  def _key(self) -> tuple:
    return tuple((v.tobytes(), v.dtype.str, v.shape) if isinstance(v, np.ndarray) else v
                 for v in dataclasses.astuple(self))

  def __hash__(self) -> int:  # by value: a static argument of the jitted substep (simulator.py)
    return hash(self._key())

  def __eq__(self, other) -> bool:
    return isinstance(other, TrackModel) and self._key() == other._key()

  @staticmethod
  def create(m: mujoco.MjModel, layout: Layout, mu_along: float, mu_across: float,
             track_separation: float, steering_efficiency: float) -> "TrackModel":
    return TrackModel(geom_belt=layout.geom_belt, belt_side=BELT_SIDE,
                      chassis_body=layout.chassis_body, mu_along=mu_along, mu_across=mu_across,
                      track_separation=track_separation, steering_efficiency=steering_efficiency,
                      contact_row0=mjx_private.contact_row0(m))


def _normalize(x: jax.Array, eps: float = 1e-9) -> tuple[jax.Array, jax.Array]:
  n = jnp.linalg.norm(x, axis=-1, keepdims=True)
  return x / jnp.maximum(n, eps), n[..., 0]


def contact_belt_velocity(m, d, tm: TrackModel, belt_speeds: jax.Array):
  """Per contact: on-belt mask, sign of the belt in the pair, belt direction, target velocity.

  The target velocity (world, m/s) is that of the belt surface relative to its body, plus the
  turn's lateral skid: the ground moves at it relative to the robot's contact point.
  """
  c = mjx_private.contacts(d)
  geom_belt = jnp.asarray(tm.geom_belt)
  b1, b2 = geom_belt[c.geom[:, 0]], geom_belt[c.geom[:, 1]]
  first = b1 >= 0
  belt = jnp.where(first, b1, b2)
  on_belt = belt >= 0
  belt_idx = jnp.maximum(belt, 0)
  g = jnp.where(first, c.geom[:, 0], c.geom[:, 1])
  sign = jnp.where(first, 1.0, -1.0)  # target (v2 - v1) = sign * u_vec

  # radial direction from the capsule's axis segment (local z, half-length size[1]) to the contact
  axis = d.geom_xmat[g][:, :, 2]
  half = m.geom_size[g, 1]
  rel = c.pos - d.geom_xpos[g]
  along = jnp.clip(jnp.sum(rel * axis, -1), -half, half)
  radial, _ = _normalize(rel - along[:, None] * axis)
  lateral = d.xmat[jnp.asarray(m.geom_bodyid)[g]][:, :, 1]
  u_dir = jnp.cross(lateral, radial)

  # steering efficiency: scale each contact's differential speed by its lateral arm
  v_bar = 0.5 * (belt_speeds[0] + belt_speeds[1])
  omega = tm.steering_efficiency * (belt_speeds[1] - belt_speeds[0]) / tm.track_separation
  chassis = d.xmat[tm.chassis_body]
  offset = c.pos - d.xpos[tm.chassis_body]
  x_c, y_c = offset @ chassis[:, 0], offset @ chassis[:, 1]
  gain = tm.steering_efficiency * jnp.abs(y_c) / (0.5 * tm.track_separation)
  speed = v_bar + gain * (belt_speeds[belt_idx] - v_bar)
  skid = -(omega * x_c)[:, None] * chassis[:, 1]
  return on_belt, sign, u_dir, speed[:, None] * u_dir + skid


def apply_belt_contacts(m, d, tm: TrackModel, belt_speeds: jax.Array, mu_scale: jax.Array | None = None):
  """Turns belt contacts' frames and friction ((mu_along, mu_across), each times mu_scale (2,) where
  given: a randomized episode's); returns (data, per-contact target slips (ncon, 2))."""
  c = mjx_private.contacts(d)
  on_belt, sign, u_dir, target = contact_belt_velocity(m, d, tm, belt_speeds)
  n = c.frame[:, 0]
  t1, t1_norm = _normalize(u_dir - jnp.sum(u_dir * n, -1, keepdims=True) * n)
  valid = on_belt & (t1_norm > 1e-3)  # a belt seen edge-on (side face) keeps isotropic friction
  t2 = jnp.cross(n, t1)
  frame = jnp.where(valid[:, None, None], jnp.stack([n, t1, t2], axis=1), c.frame)
  mu = jnp.array([tm.mu_along, tm.mu_across])
  mu = mu if mu_scale is None else mu * mu_scale
  friction = jnp.where(valid[:, None], c.friction.at[:, :2].set(mu), c.friction)
  u_vec = sign[:, None] * target
  slip = jnp.stack([jnp.sum(u_vec * t1, -1), jnp.sum(u_vec * t2, -1)], axis=-1)
  slip = jnp.where(valid[:, None], slip, 0.0)
  d = mjx_private.with_contacts(d, c.replace(frame=frame, friction=friction))
  return d, slip


def aref_shift(m, d, tm: TrackModel, slip: jax.Array) -> jax.Array:
  """Change of efc_aref that makes the friction rows target the belt slip instead of zero."""
  c = mjx_private.contacts(d)
  ncon = c.dist.shape[0]
  pos = c.dist - c.includemargin
  b = mjx_private.contact_damping(m, c.solref, c.solimp, pos)
  active = (pos < 0).astype(slip.dtype)
  per_dir = (b * active)[:, None] * c.friction[:, :2] * slip  # (ncon, 2)
  rows = jnp.stack([per_dir[:, 0], -per_dir[:, 0], per_dir[:, 1], -per_dir[:, 1]], axis=1)
  nefc = mjx_private.efc_rows(d)
  shift = jnp.zeros(nefc, rows.dtype)
  return jax.lax.dynamic_update_slice(shift, rows.reshape(4 * ncon), (tm.contact_row0,))

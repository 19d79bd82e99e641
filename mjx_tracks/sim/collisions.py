"""Collision watch: whether the robot touches what it must not (walls, obstacles) in a physics step.

A contact counts when its geoms penetrate (dist - includemargin < 0, the contacts the solver acts
on) and one of them is a robot geom (a body other than the world) while the other is
- a `forbidden` world geom (walls, wall obstacles): any part of the robot, belts included, or
- a `belts_only` world geom (floor obstacles, driven over on the belts): any robot geom but a belt.
The scene kind names both sets (scenes.kinds: SceneKind.collision_geoms). footprint_half: the box
of the robot's colliding geoms at rest, whose distance from walls scenes.clearance measures.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import mujoco
import numpy as np

from mjx_tracks.sim import mjx_private
from mjx_tracks.sim.layout import Layout


@dataclasses.dataclass(frozen=True)
class CollisionWatch:
  """Per-geom masks of one compiled model (numpy, resolved once)."""

  forbidden: np.ndarray  # (ngeom,) bool: no robot geom may touch it
  belts_only: np.ndarray  # (ngeom,) bool: only belt geoms may touch it
  robot: np.ndarray  # (ngeom,) bool: the robot's geoms
  belt: np.ndarray  # (ngeom,) bool: track belt geoms

  @staticmethod
  def create(m: mujoco.MjModel, layout: Layout, forbidden: tuple[str, ...],
             belts_only: tuple[str, ...]) -> "CollisionWatch":
    def mask(names):
      out = np.zeros(m.ngeom, bool)
      for n in names:
        g = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, n)
        if g < 0:
          raise KeyError(f"model has no geom named {n!r}")
        out[g] = True
      return out
    return CollisionWatch(mask(forbidden), mask(belts_only), np.asarray(m.geom_bodyid) > 0, layout.geom_belt >= 0)

  @property
  def active(self) -> bool:
    """Whether anything is watched (else touching() is always False)."""
    return bool(self.forbidden.any() or self.belts_only.any())

  def touching(self, d) -> jax.Array:
    """() bool: whether a contact of the step just taken is a collision (module docstring)."""
    return jnp.any(self.colliding(d))

  def colliding(self, d) -> jax.Array:
    """(contacts,) bool: which contacts of the step just taken are collisions (their geom pairs:
    mjx_private.contacts(d).geom)."""
    g1, g2, touching = penetrating(d)
    robot, belt = jnp.asarray(self.robot), jnp.asarray(self.belt)
    forbidden, belts_only = jnp.asarray(self.forbidden), jnp.asarray(self.belts_only)

    def hits(world, part):
      return robot[part] & (forbidden[world] | (belts_only[world] & ~belt[part]))

    return touching & (hits(g1, g2) | hits(g2, g1))

  def riding(self, d) -> jax.Array:
    """() bool: whether a belt touches a `belts_only` geom (a floor obstacle under the tracks) in the
    contacts of the step just taken."""
    g1, g2, touching = penetrating(d)
    belt, belts_only = jnp.asarray(self.belt), jnp.asarray(self.belts_only)
    return jnp.any(touching & ((belts_only[g1] & belt[g2]) | (belts_only[g2] & belt[g1])))


def penetrating(d) -> tuple[jax.Array, jax.Array, jax.Array]:
  """(geom 1, geom 2, whether they penetrate) of each contact of the step just taken: the contacts the
  solver acts on (dist - includemargin < 0)."""
  c = mjx_private.contacts(d)
  return c.geom[:, 0], c.geom[:, 1], c.dist - c.includemargin < 0


def robot_at_rest(m: mujoco.MjModel) -> tuple[mujoco.MjData, np.ndarray]:
  """The model's data at qpos0 (mj_forward: level, at rest) and the ids of the robot's colliding
  geoms (a body other than the world, a contype or conaffinity bit)."""
  d = mujoco.MjData(m)
  mujoco.mj_forward(m, d)
  return d, np.flatnonzero((m.geom_bodyid > 0) & ((m.geom_contype | m.geom_conaffinity) > 0))


def footprint_half(m: mujoco.MjModel, chassis_body: int) -> tuple[float, float]:
  """(hx, hy) m: half-sizes of the smallest rectangle centred on the chassis origin, level at rest
  (qpos0), holding every colliding geom of the robot (each geom's own bounding box, in its frame)."""
  d, g = robot_at_rest(m)
  aabb = np.asarray(m.geom_aabb)[g]  # (n, 6): centre and half-size in the geom's frame
  signs = np.array(np.meshgrid(*[[-1.0, 1.0]] * 3)).reshape(3, -1).T  # (8, 3)
  local = aabb[:, None, :3] + signs[None] * aabb[:, None, 3:]  # (n, 8, 3)
  world = d.geom_xpos[g, None] + np.einsum("nij,nkj->nki", d.geom_xmat[g].reshape(-1, 3, 3), local)
  rel = world[..., :2] - d.xpos[chassis_body, :2]
  return float(np.abs(rel[..., 0]).max()), float(np.abs(rel[..., 1]).max())

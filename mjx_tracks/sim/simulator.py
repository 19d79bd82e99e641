"""The simulator: one robot in one world, stepped by MJX with the track-contact model."""

from __future__ import annotations

import copy
import dataclasses
import functools

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
from mujoco import mjx

from mjx_tracks.sim import mjx_private
from mjx_tracks.sim.collisions import CollisionWatch
from mjx_tracks.sim.layout import Layout, resolve_layout
from mjx_tracks.sim.physics import PhysicsConfig, compile_model
from mjx_tracks.robots.spec import RobotSpec
from mjx_tracks.sim.tracks import TrackModel, apply_belt_contacts, aref_shift

SPAWN_CLEARANCE = 0.005  # m, the chassis spawns this far above resting height, then settles


# jitted at module level, tm static (hashed by value): a process traces each model's substep once and
# every later program of that model reuses it (a tenth of the trace; XLA inlines the call, so the
# compiled program is the same); tests/test_trace_cache.py
@functools.partial(jax.jit, static_argnums=2)
def step_with_tracks(m: mjx.Model, d: mjx.Data, tm: TrackModel, belt_speeds: jax.Array,
                     mu_scale: jax.Array | None = None) -> mjx.Data:
  """One physics substep: mjx.step with the belt contacts of the track model (its belt friction
  (along, across) times mu_scale where given)."""
  return mjx_private.step(m, d, lambda m, d: apply_belt_contacts(m, d, tm, belt_speeds, mu_scale),
                          lambda m, d, slip: aref_shift(m, d, tm, slip))


def runs_late_command(substep, delay) -> jax.Array:
  """Whether substep `substep` (0-based) of a control period still runs the previous command, the
  new one being `delay` substeps late."""
  return substep < delay


def yaw_quat(yaw: jax.Array) -> jax.Array:
  """Unit quaternions (w, x, y, z) of rotations by yaw (rad) about z; shape (..., 4)."""
  z = jnp.zeros_like(yaw)
  return jnp.stack([jnp.cos(yaw / 2), z, z, jnp.sin(yaw / 2)], axis=-1)


@dataclasses.dataclass(frozen=True)
class Simulator:
  """A compiled robot + world; pure step functions, nothing changes after construction."""

  robot: RobotSpec
  physics: PhysicsConfig
  mj_model: mujoco.MjModel
  model: mjx.Model
  layout: Layout
  tracks: TrackModel

  @staticmethod
  def create(robot: RobotSpec, world_xml: str, physics: PhysicsConfig) -> "Simulator":
    mj_model = compile_model(robot, world_xml, physics)
    layout = resolve_layout(mj_model, robot)
    tracks = TrackModel.create(mj_model, layout, robot.mu_along, robot.mu_across,
                               robot.track_separation, robot.steering_efficiency)
    # this process's first device: MJX's default, jax.devices()[0], belongs to process 0 under jax.distributed
    model = mjx.put_model(mj_model, impl="jax", device=jax.local_devices()[0])
    return Simulator(robot, physics, mj_model, model, layout, tracks)

  def with_boxes(self, box_pos: jax.Array, box_size: jax.Array, box_yaw: jax.Array | None = None) -> mjx.Model:
    """The model with this environment's scene boxes (centres, half-sizes in m, yaws in rad; None:
    axis-aligned as compiled) swapped in."""
    ids = jnp.asarray(self.layout.scene_boxes)
    m = self.model
    m = m.replace(
        geom_pos=m.geom_pos.at[ids].set(box_pos),
        geom_size=m.geom_size.at[ids].set(box_size),
        geom_rbound=m.geom_rbound.at[ids].set(jnp.linalg.norm(box_size, axis=-1)),
    )
    return m if box_yaw is None else m.replace(geom_quat=m.geom_quat.at[ids].set(yaw_quat(box_yaw)))

  def c_model_with_boxes(self, box_pos, box_size, box_yaw=None) -> mujoco.MjModel:
    """A copy of the MuJoCo C model with one environment's scene boxes (for rendering, oracles)."""
    mj = copy.copy(self.mj_model)
    ids = self.layout.scene_boxes
    mj.geom_pos[ids], mj.geom_size[ids] = np.asarray(box_pos), np.asarray(box_size)
    # the C engine's collision reads bounding spheres and boxes compiled for the boxes' old places:
    # resize them, and skip the world body's compiled bounding-volume tree (its midphase)
    mj.geom_rbound[ids] = np.linalg.norm(np.asarray(box_size), axis=-1)
    mj.geom_aabb[ids] = np.concatenate([np.zeros_like(np.asarray(box_size)), np.asarray(box_size)], axis=-1)
    mj.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_MIDPHASE
    if box_yaw is not None:
      mj.geom_quat[ids] = np.asarray(yaw_quat(jnp.asarray(box_yaw)))
      mj.geom_sameframe[ids] = mujoco.mjtSameFrame.mjSAMEFRAME_NONE  # else the compiled "same rotation as the body" wins
    return mj

  def init_data(self, pos: jax.Array, yaw: jax.Array, joint_angles: jax.Array | None = None) -> mjx.Data:
    """Data with the chassis resting at ground point pos (m) with heading yaw (rad), its joints at
    joint_angles (rad; None: 0), raised where lowered flippers would reach below the ground
    (RobotSpec.pose_lift)."""
    d = mjx.make_data(self.model, impl="jax", device=jax.local_devices()[0])
    lift = 0.0 if joint_angles is None else self.robot.pose_lift(joint_angles, jnp)
    qpos = d.qpos.at[0:3].set(pos + jnp.array([0.0, 0.0, self.robot.spawn_height + SPAWN_CLEARANCE]))
    qpos = qpos.at[2].add(lift)  # m
    qpos = qpos.at[3:7].set(yaw_quat(jnp.asarray(yaw, jnp.float32)))
    if joint_angles is not None:
      qpos = qpos.at[self.layout.joint_qpos].set(joint_angles)
      # committed to the device like make_data's arrays (a caller's jnp.zeros is not: a jitted step
      # given this data, then its own output, compiled twice; committedness is in jit's key)
      d = d.replace(ctrl=d.ctrl.at[:].set(joint_angles))
    return d.replace(qpos=qpos)

  def substep(self, m: mjx.Model, d: mjx.Data, belt_speeds: jax.Array,
              mu_scale: jax.Array | None = None) -> mjx.Data:
    """One physics step of timestep seconds with the given belt speeds (m/s, order of BELTS)."""
    return step_with_tracks(m, d, self.tracks, belt_speeds, mu_scale)

  def advance(self, m: mjx.Model, d: mjx.Data, belt_speeds: jax.Array, joint_targets: jax.Array,
              n_substeps, **late) -> mjx.Data:
    """Sets the joint servo targets (rad), then runs n_substeps physics steps (late: see _run)."""
    return self._run(m, d, belt_speeds, joint_targets, n_substeps, None, **late)[0]

  def advance_watching(self, m: mjx.Model, d: mjx.Data, belt_speeds: jax.Array, joint_targets: jax.Array,
                       n_substeps, watch: CollisionWatch, **late) -> tuple[mjx.Data, jax.Array]:
    """advance(), and whether any of its substeps' contacts was a collision (watch.touching)."""
    return self._run(m, d, belt_speeds, joint_targets, n_substeps, watch, **late)

  def _run(self, m, d, belts, targets, n_substeps, watch: CollisionWatch | None, mu_scale: jax.Array | None = None,
           held: tuple[jax.Array, jax.Array] | None = None, delay=0) -> tuple[mjx.Data, jax.Array]:
    """n_substeps (an int, or traced: a jittered period) physics steps with the command (belt speeds
    m/s, joint targets rad); held: the previous command's (belt speeds, joint targets), which act
    for the first `delay` substeps (a late command); mu_scale: (2,) x the belts' friction (along, across)."""
    def substep(i, carry):
      x, hit = carry
      b = belts
      if held is not None:
        late = runs_late_command(i, delay)
        b = jnp.where(late, held[0], belts)
        x = x.replace(ctrl=jnp.where(late, held[1], targets))
      x = self.substep(m, x, b, mu_scale)
      return x, (hit | watch.touching(x)) if watch is not None else hit
    return jax.lax.fori_loop(0, n_substeps, substep, (d.replace(ctrl=targets), jnp.bool_(False)))

  def plain_step(self, m: mjx.Model, d: mjx.Data) -> mjx.Data:
    """mjx.step without the track model (benchmark baseline)."""
    return mjx.step(m, d)


def staircase_simulator(robot: RobotSpec, physics: PhysicsConfig, n_max: int | None = None) -> Simulator:
  """A simulator of the robot in the staircase world (pool of step boxes)."""
  from scenes import staircase
  return Simulator.create(robot, staircase.world_xml(n_max or staircase.N_MAX), physics)

"""Ids and index tables of a compiled robot model, resolved once by name."""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np

from mjx_tracks.robots.mjcf import CHASSIS_BODY
from mjx_tracks.robots.spec import RobotSpec
from scenes.world import SCENE_BOX

BELTS = ("track_left", "track_right", "flipper_front_left", "flipper_front_right",
         "flipper_rear_left", "flipper_rear_right")
BELT_SIDE = np.array([1.0, -1.0, 1.0, -1.0, 1.0, -1.0], np.float32)  # +1 left, -1 right


@dataclasses.dataclass(frozen=True)
class Layout:
  """Where everything lives in qpos / qvel / ctrl / geoms of one model."""

  chassis_body: int
  joint_qpos: np.ndarray  # (n_joints,) qpos address of each flipper / arm joint
  joint_qvel: np.ndarray  # (n_joints,) dof address
  joint_limits: np.ndarray  # (n_joints, 2) rad
  joint_names: tuple[str, ...]
  geom_belt: np.ndarray  # (ngeom,) belt index of each geom (order of BELTS), -1 if none
  scene_boxes: np.ndarray  # (n_boxes,) geom ids of the per-environment boxes, in name order
  camera_site: int

  @property
  def n_joints(self) -> int:
    return len(self.joint_qpos)


def resolve_layout(m: mujoco.MjModel, robot: RobotSpec) -> Layout:
  """Looks every id up by name once; fails loudly if the model lacks one."""

  def gid(kind, name):
    i = mujoco.mj_name2id(m, kind, name)
    if i < 0:
      raise KeyError(f"model has no {kind.name} named {name!r}")
    return i

  names = robot.joint_names()
  jids = [gid(mujoco.mjtObj.mjOBJ_JOINT, n) for n in names]
  geom_belt = np.full(m.ngeom, -1, np.int32)
  steps = []
  for g in range(m.ngeom):
    name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g) or ""
    if name.startswith("belt_"):
      belt = name[len("belt_"):]
      belt = belt.rsplit("_", 1)[0] if belt.startswith("flipper_") else belt
      geom_belt[g] = BELTS.index(belt)
    elif name.startswith(SCENE_BOX) and name[len(SCENE_BOX):].isdigit():
      steps.append((int(name[len(SCENE_BOX):]), g))
  return Layout(
      chassis_body=gid(mujoco.mjtObj.mjOBJ_BODY, CHASSIS_BODY),
      joint_qpos=np.array([m.jnt_qposadr[j] for j in jids], np.int32),
      joint_qvel=np.array([m.jnt_dofadr[j] for j in jids], np.int32),
      joint_limits=robot.joint_limits(),
      joint_names=names,
      geom_belt=geom_belt,
      scene_boxes=np.array([g for _, g in sorted(steps)], np.int32),
      camera_site=gid(mujoco.mjtObj.mjOBJ_SITE, "depth_camera"),
  )

"""What MJX's contact culling (physics.contact_slots, physics.box_pairs) would lose along a drive,
judged by MuJoCo's C engine, which keeps every pair and contact: the oracle of the culling settings
(tests/test_stairs_physics.py, `python -m train.bench gate`)."""

from __future__ import annotations

import mujoco
import numpy as np

from scenes import staircase as sc


def culling_figures(sim, stairs: sc.Staircase, qpos: np.ndarray) -> tuple[int, int]:
  """(most touching contacts at one state, worst rank of a touching belt-box pair) over the states
  qpos (T, nq) of a drive on `stairs`. A pair's rank is its place among all belt-box pairs ordered
  as MJX orders them for max_geom_pairs (centre distance minus both bounding-sphere radii, nearest
  first, 0-based); -1 when no belt touches a box. Culling loses nothing when the first figure is
  <= contact_slots and the second < box_pairs."""
  box_pos, box_size = (np.asarray(x) for x in sc.step_boxes(stairs))
  mj = sim.c_model_with_boxes(box_pos, box_size)
  boxes = np.asarray(sim.layout.scene_boxes)
  belts = np.flatnonzero((mj.geom_type == mujoco.mjtGeom.mjGEOM_CAPSULE) & (mj.geom_contype != 0))
  d = mujoco.MjData(mj)
  most, worst = 0, -1
  for q in np.asarray(qpos):
    d.qpos[:] = q
    mujoco.mj_forward(mj, d)
    touching = [(c.geom1, c.geom2) for c in d.contact[:d.ncon] if c.dist < 0]
    most = max(most, len(touching))
    gap = (np.linalg.norm(d.geom_xpos[belts][:, None] - d.geom_xpos[boxes][None], axis=-1)
           - mj.geom_rbound[belts][:, None] - mj.geom_rbound[boxes][None])  # MJX's ranking distance
    rank = np.argsort(np.argsort(gap.ravel(), kind="stable")).reshape(gap.shape)
    for g1, g2 in touching:
      for g, b in ((g1, g2), (g2, g1)):
        if g in belts and b in boxes:
          worst = max(worst, int(rank[np.flatnonzero(belts == g)[0], np.flatnonzero(boxes == b)[0]]))
  return most, worst

"""scripts/analysis/nav_collision_contacts.py: its names of a contact's geom pair (the pairs come
from CollisionWatch.colliding, checked against the C engine in tests/test_collisions.py)."""

import os
import sys

import mujoco

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "scripts", "analysis"))
from nav_collision_contacts import GONE, pair_name  # noqa: E402

import mjx_tracks  # noqa: E402


def test_a_pair_is_named_robot_geom_first_and_a_nameless_geom_by_its_body():
  m = mjx_tracks.load("nav-obstacles").sim.mj_model
  geom = lambda name: mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, name)  # noqa: E731
  belt, wall = geom("belt_flipper_front_left_1"), geom("wall_left")
  assert pair_name(m, (wall, belt)) == pair_name(m, (belt, wall)) == "belt_flipper_front_left_1 -> wall_left"
  nameless = next(g for g in range(m.ngeom) if m.geom_bodyid[g] > 0 and mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g) is None)
  body = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, m.geom_bodyid[nameless])
  assert pair_name(m, (wall, nameless)) == f"geom of {body} -> wall_left"
  assert pair_name(m, (-1, -1)) == GONE

"""scripts/analysis/nav_riding.py: its tally of riding and collisions against hand-made trials (the
rollout it drives is train.evaluate's, tested elsewhere)."""

import os
import sys
import types

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "scripts", "analysis"))
from nav_riding import collisions, tally  # noqa: E402


def test_riding_and_collisions_are_counted_per_trial_up_to_its_end():
  # 7 steps, 5 trials (columns): 0 rides at step 1 and collides at step 2 (done); 1 rides at step 0,
  # reaches the goal at step 1, "rides" and "collides" after its end (not counted); 2 never rides and
  # collides at step 5 (done); 3 rides at step 1 and collides at step 5: 4 steps before, just outside a
  # window of 4 (steps 2-5); 4 rides at step 2 and collides at step 5: just inside it
  riding, collided, done = (np.zeros((7, 5), bool) for _ in range(3))
  riding[1, 0], collided[2, 0], done[2, 0] = True, True, True
  riding[0, 1], done[1, 1], riding[3, 1], collided[4, 1] = True, True, True, True
  collided[5, 2], done[5, 2] = True, True
  riding[1, 3], collided[5, 3], done[5, 3] = True, True, True
  riding[2, 4], collided[5, 4], done[5, 4] = True, True, True
  t = tally(riding, collided, done, window=4)
  assert t == {"trials": 5, "rode": 4, "rode_collided": 3, "never_rode": 1, "never_rode_collided": 1,
               "collided": 4, "collided_riding_in_window": 2, "riding_steps_mean": 0.8}


def test_each_collision_lists_its_step_riding_and_nearest_floor_obstacle():
  # 3 steps, 3 trials; boxes 0-1 are the area's wall obstacles (never measured), 2-3 floor obstacles.
  # Trial 0 rides at step 0 and collides at step 1 with its chassis at (1, 0): its floor box 2 is a
  # 0.2 x 0.2 m square (half 0.1) centred at (1.5, 0), its footprint 0.4 m away; box 3 far. Trial 1
  # collides at step 2 after reaching the goal at step 0 (not listed). Trial 2 collides at step 0 at
  # (1, 0), its own floor box 2 centred at (2.5, 0): 1.4 m.
  riding, collided, done = (np.zeros((3, 3), bool) for _ in range(3))
  riding[0, 0], collided[1, 0], done[1, 0] = True, True, True
  done[0, 1], collided[2, 1] = True, True
  collided[0, 2], done[0, 2] = True, True
  xy = np.zeros((3, 3, 2))
  xy[1, 0], xy[0, 2] = [1.0, 0.0], [1.0, 0.0]
  pos = np.zeros((3, 4, 3))
  pos[:, 0, :2], pos[:, 1, :2], pos[:, 2, :2], pos[:, 3, :2] = [1.0, 0.0], [1.0, 0.0], [1.5, 0.0], [9.0, 9.0]
  pos[2, 2, :2] = [2.5, 0.0]
  scene = types.SimpleNamespace(box_pos=pos, box_size=np.full((3, 4, 3), 0.1), box_yaw=np.zeros((3, 4)))
  rows = collisions(riding, collided, done, xy, scene, window=4)
  assert rows == [{"trial": 0, "step": 1, "riding_in_window": True, "floor_box_m": 0.4},
                  {"trial": 2, "step": 0, "riding_in_window": False, "floor_box_m": 1.4}]

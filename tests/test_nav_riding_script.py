"""scripts/analysis/nav_riding.py: its tally of riding and collisions against hand-made trials (the
rollout it drives is train.evaluate's, tested elsewhere)."""

import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "scripts", "analysis"))
from nav_riding import tally  # noqa: E402


def test_riding_and_collisions_are_counted_per_trial_up_to_its_end():
  # 6 steps, 4 trials (columns): 0 rides at step 1 and collides at step 2 (done); 1 rides at step 0,
  # reaches the goal at step 1, "rides" and "collides" after its end (not counted); 2 never rides and
  # collides at step 5 (done); 3 rides at step 0 only, collides at step 5: outside a window of 4 steps
  riding = np.zeros((6, 4), bool)
  collided = np.zeros((6, 4), bool)
  done = np.zeros((6, 4), bool)
  riding[1, 0], collided[2, 0], done[2, 0] = True, True, True
  riding[0, 1], done[1, 1], riding[3, 1], collided[4, 1] = True, True, True, True
  collided[5, 2], done[5, 2] = True, True
  riding[0, 3], collided[5, 3] = True, True
  t = tally(riding, collided, done, window=4)
  assert t == {"trials": 4, "rode": 3, "rode_collided": 2, "never_rode": 1, "never_rode_collided": 1,
               "collided": 3, "collided_riding_in_window": 1, "riding_steps_mean": 0.75}

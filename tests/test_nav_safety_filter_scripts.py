"""scripts/analysis/nav_safety_filter.py and nav_filter_trace.py: their pure parts against hand-made
inputs (the rollouts they drive are train.evaluate's, tested elsewhere)."""

import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "scripts", "analysis"))
from nav_filter_trace import COLUMNS, motion  # noqa: E402

from mjx_tracks.envs.safety_filter import SafetyFilter  # noqa: E402
from mjx_tracks.envs.scan import ScanLayout  # noqa: E402
from nav_safety_filter import ON, outcomes, paired, variants  # noqa: E402


def test_variants_parse_and_refuse_other_keys():
  assert variants([]) == {"filter on": [ON]}
  assert variants(["m:control.safety_filter.margin=0.2; control.safety_filter.rays=45"]) == {
      "m": [ON, "control.safety_filter.margin=0.2", "control.safety_filter.rays=45"]}
  for bad in (["x:reward.goal_bonus=1"], ["no colon"], ["a:", "a:"], ["as trained:"]):
    with pytest.raises(ValueError):
      variants(bad)


def test_outcomes_and_pairing_count_trials_by_hand():
  off = outcomes({"success": [1, 0, 0, 0], "collided": [0, 1, 0, 0], "tipped_over": [0, 0, 0, 1], "filtered": [0, 0, 0, 0]})
  on = outcomes({"success": [0, 1, 0, 0], "collided": [0, 0, 1, 0], "tipped_over": [0, 0, 0, 1], "filtered": [0.5, 0, 1, 0]})
  assert (off["collided"], off["timed_out"], off["tipped_over"]) == (1, 1, 1)
  assert on["filtered_steps"] == 0.375
  assert paired(off, on) == {"collisions_removed": 1, "collisions_added": 1, "successes_lost": 1, "successes_gained": 1}


def test_motion_is_read_in_the_chassis_frame():
  """Heading +y (yaw pi/2), the chassis moves 0.2 m along +y and 0.1 m along -x and turns 0.1 rad:
  0.2 m ahead, 0.1 m to its left; the prediction of 0.8 m/s straight for 0.25 s is 0.2 m ahead."""
  views = np.zeros((2, len(COLUMNS)))
  start = dict(zip(COLUMNS, views[0]), filtered_v=0.8, filtered_w=0.0, yaw=np.pi / 2)
  views[0] = [start[c] for c in COLUMNS]
  views[1] = [dict(start, x=-0.1, y=0.2, yaw=np.pi / 2 + 0.1)[c] for c in COLUMNS]
  predicted, actual = motion(_filter(0.0), views, 0, 0.25)
  assert predicted == pytest.approx([0.2, 0.0, 0.0], abs=1e-6)
  assert actual == pytest.approx([0.2, 0.1, 0.1], abs=1e-3)
  # with a response time of 0.25 s from a measured 0.4 m/s forward: 0.8 t - 0.4 tau (1 - e^-1) = 0.1368 m
  views[0, COLUMNS.index("forward")] = 0.4
  assert motion(_filter(0.25), views, 0, 0.25)[0] == pytest.approx([0.137, 0.0, 0.0], abs=1e-3)


def _filter(response):
  return SafetyFilter(ScanLayout(8, 5.0, (0.0, 0.0, 0.2), (0.0,)), (0.5, 0.4), 0.5, 10, 0.1, 1.0, 1.0, response)

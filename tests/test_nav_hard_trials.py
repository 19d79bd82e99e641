"""scripts/analysis/nav_hard_trials.py: each layout figure against a hand-built scene, the rank
correlation against hand-ranked cases, the family of the task asked for."""

import json
import os
import sqlite3
import sys

import jax
import jax.numpy as jnp
import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "scripts", "analysis"))
from nav_hard_trials import BISECTIONS, DISC_RANGE, layout_features, spearman, summarize, task_family  # noqa: E402
from shared_failures import outcomes  # noqa: E402

from mjx_tracks.envs.config import load_config  # noqa: E402
from scenes.geodesic import NODE_OFFSET  # noqa: E402
from scenes.navigation import AREA_LEN  # noqa: E402
from scenes.scene import SceneState  # noqa: E402
from scenes.world import parked_xyz  # noqa: E402


# the features of an area of AREA_LEN as one program (eager, each of its ~130 operations compiles alone)
_features = jax.jit(lambda scene: layout_features(scene, AREA_LEN))


def _scene(wall_top: float, floor_box) -> SceneState:
  """Wall obstacle 1 across the area at x = 6 m, 0.3 m thick, from y = -5 m up to wall_top; obstacle
  2 parked off the area; one floor box (centre x, y; half-sizes) or none (parked)."""
  walls = [([6.0, (wall_top - 5.0) / 2, 0.5], [0.15, (wall_top + 5.0) / 2, 0.5]), (parked_xyz(1), [0.1, 0.1, 0.1])]
  floor = [([*floor_box[:2], 0.05], [*floor_box[2:], 0.05])] if floor_box else [(parked_xyz(2), [0.1, 0.1, 0.1])]
  pos, size = (jnp.array([b[i] for b in walls + floor], jnp.float32) for i in (0, 1))
  w1 = wall_top + 5.0  # how far it juts from its wall: the opening beside its end is 10 - w1
  return SceneState(pos, size, jnp.zeros(3), jnp.array([1.0, 0.0, 0.0]), jnp.float32(-0.5), jnp.array([11.0, 2.0, 0.085]),
                    jnp.float32(0.0), jnp.array([w1, 0.3, 0.0, 0.3, 1.5]), jnp.int32(1))


def test_the_widest_disc_is_half_the_opening_and_a_floor_box_in_it_narrows_it():
  # the bisection's resolution, and the geodesic's corner nodes sit NODE_OFFSET outside their
  # inflated boxes, which takes that much off a disc that just fits
  tol = (DISC_RANGE[1] - DISC_RANGE[0]) / 2 ** BISECTIONS + NODE_OFFSET
  open_2m = _features(_scene(3.0, None))  # opening y in [3, 5]: a disc of radius 1 m passes
  assert float(open_2m["widest_disc"]) == pytest.approx(1.0, abs=tol)
  assert float(open_2m["opening_1"]) == pytest.approx(2.0) and float(open_2m["gap_C"]) == 1.5
  assert float(open_2m["floor_obstacles_kept"]) == 0 and np.isinf(float(open_2m["floor_to_wall_obstacle"]))
  assert float(open_2m["spawn_yaw_abs"]) == pytest.approx(0.5) and float(open_2m["goal_y"]) == pytest.approx(2.0)
  # a 0.4 m box in the opening, y in [3.6, 4.0], 0.45 m past the wall's face (x 6.6 - 6.15): the
  # widest way is between the box and the outer wall, 1.0 m wide (a disc of 0.5 m); between box and
  # wall end the corners lie 0.75 m apart, and the geodesic's square inflation closes that way for
  # discs over 0.3 m (0.6 m across in y)
  boxed = _features(_scene(3.0, (6.8, 3.8, 0.2, 0.2)))
  assert float(boxed["widest_disc"]) == pytest.approx(0.5, abs=tol)
  assert float(boxed["floor_to_wall_obstacle"]) == pytest.approx(np.hypot(0.45, 0.6), abs=1e-5)
  assert float(boxed["floor_obstacles_kept"]) == 1
  closed = _features(_scene(5.0, None))  # the wall closes the area: no way at all
  assert float(closed["widest_disc"]) == 0.0


def test_rank_correlation_against_hand_ranked_cases():
  x = np.array([1.0, 2.0, 3.0, 4.0])
  assert spearman(x, x ** 3) == pytest.approx(1.0) and spearman(x, -x) == pytest.approx(-1.0)
  # ties share their mean rank: ranks (0.5, 0.5, 2, 3) against (0, 1, 2, 3)
  r = np.array([0.5, 0.5, 2.0, 3.0])
  assert spearman(np.array([1.0, 1.0, 2.0, 3.0]), x) == pytest.approx(np.corrcoef(r, np.arange(4))[0, 1])
  assert spearman(np.ones(4), x) is None  # a constant has no ranks


def test_the_summary_lists_the_most_collided_trials_first_and_averages_the_clean_ones():
  counts = np.array([0, 5, 0, 2, 9])
  feats = {"gap_C": np.array([1.0, 1.1, 3.0, 1.3, 1.2])}
  s = summarize(counts, feats, worst=2)
  assert [(r["trial"], r["policies"]) for r in s["worst_trials"]] == [(4, 9), (1, 5)]
  assert s["trials_none_collided_in"] == 2 and s["mean_of_trials_none_collided_in"]["gap_C"] == pytest.approx(2.0)


def test_the_family_read_is_the_tasks_own_not_a_larger_one_of_a_task_named_like_a_variant(tmp_path):
  db = str(tmp_path / "study.sqlite")
  nav, obstacles = (json.dumps(load_config(t).to_dict()) for t in ("nav", "nav-obstacles"))
  runs = [("a", "nav", nav), ("b", "nav-obstacles", obstacles), ("c", "nav-obstacles", obstacles)]
  with sqlite3.connect(db) as c:
    c.execute("CREATE TABLE experiments (run_id TEXT, task TEXT, algo TEXT, config_json TEXT)")
    c.execute("CREATE TABLE evals (run_id TEXT, scene TEXT, trial INTEGER, success REAL, collided REAL)")
    c.executemany("INSERT INTO experiments VALUES (?, ?, 'ppo', ?)", runs)
    c.executemany("INSERT INTO evals VALUES (?, 'nav/zigzag', 0, 1.0, 0.0)", [(r[0],) for r in runs])
  tables = outcomes([db], "nav/zigzag", "nav", "collided")  # "nav" keeps nav-... as variants
  assert sorted(len(t) for t in tables.values()) == [1, 2]
  assert list(task_family(db, tables, "nav")) == [f"{db}:a"]
  assert sorted(task_family(db, tables, "nav-obstacles")) == [f"{db}:b", f"{db}:c"]

"""What do the navigation trials that many policies collide in have in common? For one evaluation area
(e.g. nav/zigzag) and the trained runs of a task in a study database: how many policies of the
largest scene family with a run of that task (scripts/analysis/shared_failures.py: runs whose
`scene` config is the same draw the same layout for the same trial) collided in each trial, and each
trial's layout drawn again as `train.evaluate` drew it (the family's config, the area's draw, reset
keys split from EVAL_SEED): the area's gap C, the two openings beside the wall obstacles' free ends
(m; in a hallway: the area's width less each obstacle's jut), how far the nearest floor obstacle
lies from a wall obstacle (m, footprint to footprint), the widest disc with a way round every
obstacle from the spawn to the goal (m; bisection, not capped by C as the scene caps its passage),
the spawn's heading and the goal's side. Prints the trials most policies collided in beside the
means of the trials none collided in, and a Spearman rank correlation of each feature with the count
(none for a feature that never varies); writes JSON with every trial's count and figures (and with
--plot a plan view of the worst trials) with the device, command and date. CPU, resets only (no
policy is run).

python scripts/analysis/nav_hard_trials.py results/studies/nav/study.sqlite --task nav-obstacles \
    --area nav/zigzag --out results/nav/hard-trials-zigzag-cpu.json --plot results/nav/hard-trials-zigzag.png
"""

from __future__ import annotations

import argparse
import json
import sys

import jax
import jax.numpy as jnp
import numpy as np

from mjx_tracks import atomic
from mjx_tracks.envs.config import from_dict
from scenes.navigation import AREA_W, WALL_OBSTACLES, path_around
from scenes.world import is_parked
from shared_failures import outcomes, shared_trials  # scripts/analysis/shared_failures.py (this script's folder is on sys.path)
from provenance import provenance  # scripts/analysis/provenance.py
from train.db import read_only
from train.evaluation import EVAL_EPS, EVAL_SEED, scene_env, trial_keys, trial_starts

DISC_RANGE = (0.05, 2.0)  # m, the widest disc's bisection interval
BISECTIONS = 12  # its resolution: 2 m / 2^12 ~ 0.5 mm


def run_config_in(db: str, run_key: str):
  """The task config of one run ("db:run_id", as shared_failures.outcomes keys it)."""
  with read_only(db) as c:
    (config_json,) = c.execute("SELECT config_json FROM experiments WHERE run_id = ?",
                               (run_key[len(db) + 1:],)).fetchone()
  return from_dict(json.loads(config_json))


def task_family(db: str, tables: dict, task: str) -> dict:
  """The largest family (shared_failures.outcomes) with a run of exactly `task` (outcomes also keeps
  its variants, TASK-..., which for nav include other tasks: nav-obstacles); else the largest."""
  with read_only(db) as c:
    own_runs = {f"{db}:{r}" for (r,) in c.execute("SELECT run_id FROM experiments WHERE task = ?", (task,))}
  own = [t for t in tables.values() if own_runs & set(t)]
  return max(own or tables.values(), key=len)


def rect_gap(pos_a, half_a, pos_b, half_b):
  """Distance (m) between two axis-aligned rectangles (centres, half-sizes (2,)); 0 if they overlap."""
  d = jnp.maximum(jnp.abs(pos_a - pos_b) - half_a - half_b, 0.0)
  return jnp.linalg.norm(d)


def widest_disc(s, length: float):
  """The largest disc radius (m) with a way from the spawn to the goal round every box of scene s."""
  def ok(r):
    return jnp.isfinite(path_around(s.spawn_pos[:2], s.goal[:2], s.box_pos[:, :2], s.box_size[:, :2], r, length))

  def halve(_, lo_hi):
    lo, hi = lo_hi
    mid = (lo + hi) / 2
    passes = ok(mid)
    return jnp.where(passes, mid, lo), jnp.where(passes, hi, mid)
  lo, _ = jax.lax.fori_loop(0, BISECTIONS, halve, (jnp.float32(DISC_RANGE[0]), jnp.float32(DISC_RANGE[1])))
  return jnp.where(ok(DISC_RANGE[0]), lo, 0.0)


def layout_features(s, length: float) -> dict:
  """One trial's layout figures (m, rad), the module docstring's."""
  walls_pos, walls_half = s.box_pos[:WALL_OBSTACLES, :2], s.box_size[:WALL_OBSTACLES, :2]
  floor_pos, floor_half = s.box_pos[WALL_OBSTACLES:, :2], s.box_size[WALL_OBSTACLES:, :2]
  kept = ~is_parked(s.box_pos[WALL_OBSTACLES:])
  gaps = jax.vmap(lambda p, h: jax.vmap(lambda q, g: rect_gap(p, h, q, g))(walls_pos, walls_half))(floor_pos, floor_half)
  return {"gap_C": s.xi[4], "opening_1": AREA_W - s.xi[0], "opening_2": AREA_W - s.xi[2],
          "floor_to_wall_obstacle": jnp.min(jnp.where(kept[:, None], gaps, jnp.inf), initial=jnp.inf),
          "floor_obstacles_kept": jnp.sum(kept).astype(jnp.float32), "widest_disc": widest_disc(s, length),
          "spawn_yaw_abs": jnp.abs(s.spawn_yaw), "spawn_y": s.spawn_pos[1], "goal_y": s.goal[1]}


def trial_layouts(cfg, area: str, trials: int):
  """Trials 0 .. trials - 1's scene states as train.evaluate draws them, their layout figures and
  the area's length (m)."""
  core, draw = scene_env(cfg, area)
  scene = jax.jit(lambda keys: trial_starts(core, keys, EVAL_EPS, None, draw))(trial_keys(trials, EVAL_SEED)).pipeline_state.scene
  feats = jax.jit(jax.vmap(lambda s: layout_features(s, core.scene.length)))(scene)
  return jax.tree_util.tree_map(np.asarray, scene), {k: np.asarray(v, float) for k, v in feats.items()}, core.scene.length


def spearman(x: np.ndarray, y: np.ndarray) -> float | None:
  """Spearman's rank correlation (scipy's: average ranks for ties); None where x or y never varies."""
  from scipy.stats import spearmanr  # noqa: PLC0415  (scipy: a dependency of jax)
  return float(spearmanr(x, y).statistic) if np.ptp(x) and np.ptp(y) else None


def summarize(counts: np.ndarray, feats: dict, worst: int) -> dict:
  """The worst trials' figures, the means over the trials no policy collided in, each feature's
  rank correlation with the count."""
  order = np.argsort(-counts, kind="stable")[:worst]
  clean = counts == 0
  return {"worst_trials": [{"trial": int(t), "policies": int(counts[t]), **{k: round(float(v[t]), 3) for k, v in feats.items()}}
                           for t in order],
          "mean_of_trials_none_collided_in": {k: round(float(v[clean].mean()), 3) for k, v in feats.items()},
          "trials_none_collided_in": int(clean.sum()),
          "spearman_with_count": {k: None if (r := spearman(v, counts)) is None else round(r, 3) for k, v in feats.items()},
          "per_trial": {"collided_policies": counts.tolist(),
                        **{k: [round(float(x), 4) for x in v] for k, v in feats.items()}}}  # 4: the bisection resolves 0.5 mm


def plot(path: str, scene, counts: np.ndarray, trials: list[int], policies: int, area_len: float) -> None:
  """Plan views of the given trials: wall obstacles (dark), floor obstacles (light), spawn and heading, goal."""
  import matplotlib  # noqa: PLC0415
  matplotlib.use("Agg")
  import matplotlib.pyplot as plt  # noqa: PLC0415
  cols, rows = 4, max(1, (len(trials) + 3) // 4)
  fig, axes = plt.subplots(rows, cols, figsize=(4 * cols, 3.6 * rows))
  for ax, t in zip(np.ravel(axes), trials):
    for i, (p, h) in enumerate(zip(scene.box_pos[t, :, :2], scene.box_size[t, :, :2])):
      if not is_parked(scene.box_pos[t, i]):
        ax.add_patch(plt.Rectangle(p - h, *(2 * h), color="0.2" if i < WALL_OBSTACLES else "tab:orange", alpha=0.9))
    sp, yaw = scene.spawn_pos[t], scene.spawn_yaw[t]
    ax.plot(*sp[:2], "bo")
    ax.arrow(sp[0], sp[1], 0.8 * np.cos(yaw), 0.8 * np.sin(yaw), color="b", width=0.05)
    ax.plot(*scene.goal[t, :2], "g*", markersize=12)
    ax.set_xlim(0, area_len)
    ax.set_ylim(-AREA_W / 2, AREA_W / 2)
    ax.set_aspect("equal")
    ax.set_title(f"trial {t}: {int(counts[t])} of {policies} collided", fontsize=9)
  for ax in np.ravel(axes)[len(trials):]:
    ax.axis("off")
  fig.tight_layout()
  fig.savefig(path, dpi=80)


def main(argv: list[str] | None = None) -> int:
  p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  p.add_argument("db", help="a study database (STUDY/study.sqlite)")
  p.add_argument("--task", default="nav-obstacles", help="the task, its variants (TASK-...) included")
  p.add_argument("--area", default="nav/zigzag", help="the evaluation scene (nav/hallway, nav/zigzag, held-out/...)")
  p.add_argument("--worst", type=int, default=8, help="how many of the most-collided trials to list (and plot)")
  p.add_argument("--out", help="JSON path")
  p.add_argument("--plot", help="PNG path: plan views of the worst trials and, for comparison, the first clean ones")
  args = p.parse_args(argv)
  try:
    tables = outcomes([args.db], args.area, args.task, "collided")
  except FileNotFoundError as e:
    print(f"error: {e}", file=sys.stderr)
    return 2
  if not tables:
    print(f"error: no run of {args.task} evaluated on {args.area} in {args.db}", file=sys.stderr)
    return 2
  table = task_family(args.db, tables, args.task)
  trials = shared_trials(table)
  if trials != list(range(len(trials))):  # the layouts are drawn as trials 0 .. n - 1
    print(f"error: the family's runs share trials {trials[:5]}... of {args.area}, not 0 .. n - 1 of one "
          "evaluation", file=sys.stderr)
    return 2
  counts = np.array([sum(table[r][t] for r in table) for t in trials])
  cfg = run_config_in(args.db, next(iter(table)))
  scene, feats, area_len = trial_layouts(cfg, args.area, len(trials))
  result = {**provenance(), "area": args.area, "task": args.task, "policies": len(table),
            "collisions": int(counts.sum()), **summarize(counts, feats, args.worst)}
  for row in result["worst_trials"]:
    print(json.dumps(row))
  print("none collided in", result["trials_none_collided_in"], "trials; their means:", json.dumps(result["mean_of_trials_none_collided_in"]))
  print("spearman with the count:", json.dumps(result["spearman_with_count"]))
  if args.out:
    atomic.write_json(args.out, result)
  if args.plot:
    shown = [r["trial"] for r in result["worst_trials"]] + [t for t in trials if counts[t] == 0][:4]
    plot(args.plot, scene, counts, shown, len(table), area_len)
  return 0


if __name__ == "__main__":
  sys.exit(main())

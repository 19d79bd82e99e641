"""Do a navigation policy's collisions follow its riding on floor obstacles? Trial by trial.

Each run's exported policy drives the evaluation's trials of a navigation area (train.evaluate's
trials: the area's draw, reset keys from EVAL_SEED, eps EVAL_EPS, deterministic; the run as it was
configured), all in one batch. At the end of every control step it reads whether a track belt rides
on a floor obstacle (CollisionWatch.riding: what reward.riding_penalty charges, per step ending so)
and whether the robot collided in it; a trial ends at its first done step (goal, collision or
tip-over). Per run and in all: the trials that rode at least once and those that never did, with how
many of each collided, and of the collided trials how many rode at the end of one of the `--window`
control steps up to and including the colliding one;
each collision's trial, step, whether it rode in that window, and how far the chassis centre was from
the nearest floor obstacle's footprint after the colliding step (m, 0 over it), with how many of the
collisions without riding came within `--near` m of one.
The batch is not the evaluation's program (and this CPU is not its GPU), so a trial's path may differ
from the study's; the counts are samples of the same policy on the same layouts. Prints a line per run
and writes JSON with the device, command and date. CPU (2 cores): 8 min for five runs of 100 trials.

python scripts/analysis/nav_riding.py RUN [RUN ...] [--area nav/zigzag] [--trials 100] [--window 4] [--near 1.0] \
    --out FILE
"""

from __future__ import annotations

import argparse
import os
import sys

import jax
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
from mjx_tracks import atomic, compile_cache  # noqa: E402
from mjx_tracks.envs.config import ConfigError  # noqa: E402
from train.core.policy import act_from_params, load_policy_params  # noqa: E402
from train.core.run_record import run_config  # noqa: E402
from train.evaluation import EVAL_EPS, EVAL_SEED, live_steps, scene_env, trial_keys, trial_starts  # noqa: E402
from provenance import provenance  # noqa: E402  (scripts/analysis/provenance.py)
from nav_collision_sites import footprint_distance  # noqa: E402  (scripts/analysis/nav_collision_sites.py)
from scenes.navigation import WALL_OBSTACLES  # noqa: E402


def rollout(run_dir: str, area: str, trials: int):
  """(riding at each step's end, collided in it, done after it: each (max_steps, trials) of 0/1;
  the chassis' (x, y) after each step (max_steps, trials, 2) m; the trials' scenes)."""
  cfg = run_config(run_dir)
  core, draw = scene_env(cfg, area)
  spec, params = load_policy_params(os.path.join(run_dir, "policy"))
  act = act_from_params(spec)(params)
  start = trial_starts(core, trial_keys(trials, EVAL_SEED), EVAL_EPS, None, draw)

  def body(s, _):
    n = jax.vmap(core.step)(s, act(s.obs))
    riding = jax.vmap(lambda x: core.watch.riding(x.pipeline_state.data))(n)
    xy = n.pipeline_state.data.xpos[:, core.sim.layout.chassis_body, :2]
    return n, (riding, n.pipeline_state.collided, n.done, xy)
  *flags, xy = jax.jit(lambda s: jax.lax.scan(body, s, None, length=cfg.episode.max_steps)[1])(start)
  return (*(np.asarray(x) > 0 for x in flags), np.asarray(xy), jax.tree_util.tree_map(np.asarray, start.pipeline_state.scene))


def rode_before(riding: np.ndarray, step: np.ndarray, window: int) -> np.ndarray:
  """(trials,) bool: whether each trial rode at the end of one of the `window` steps up to and including
  its `step`."""
  return np.array([riding[max(0, f - window + 1): f + 1, k].any() for k, f in enumerate(step)], bool)


def collisions(riding, collided, done, xy, scene, window: int) -> list[dict]:
  """Each trial's first collision within its episode: trial, step, riding in the window up to it, and the
  chassis centre's distance (m) from the nearest floor obstacle's footprint after that step (None: none)."""
  hit = collided & live_steps(done)
  first = hit.argmax(axis=0)
  near = rode_before(riding, first, window)
  floor = slice(WALL_OBSTACLES, None)
  rows = []
  for k in np.flatnonzero(hit.any(axis=0)):
    f = int(first[k])
    d = footprint_distance(xy[f, k][None], scene.box_pos[k, floor, :2][None], scene.box_size[k, floor, :2][None],
                           scene.box_yaw[k, floor][None])[0]
    rows.append({"trial": int(k), "step": f, "riding_in_window": bool(near[k]),
                 "floor_box_m": round(float(d.min()), 3) if d.size else None})
  return rows


def tally(riding: np.ndarray, collided: np.ndarray, done: np.ndarray, window: int) -> dict:
  """Counts over the trials (columns), each cut at its first done step."""
  live = live_steps(done)
  rode = (riding & live).any(axis=0)
  hit = (collided & live).any(axis=0)
  near = rode_before(riding, (collided & live).argmax(axis=0), window)
  return {"trials": int(riding.shape[1]), "rode": int(rode.sum()), "rode_collided": int((rode & hit).sum()),
          "never_rode": int((~rode).sum()), "never_rode_collided": int((~rode & hit).sum()),
          "collided": int(hit.sum()), "collided_riding_in_window": int((hit & near).sum()),
          "riding_steps_mean": round(float((riding & live).sum(axis=0).mean()), 3)}


def main(argv: list[str] | None = None) -> int:
  p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  p.add_argument("runs", nargs="+", help="run folders, each with policy/")
  p.add_argument("--area", default="nav/zigzag")
  p.add_argument("--trials", type=int, default=100)
  p.add_argument("--window", type=int, default=4, help="control steps up to and including a collision's (their ends)")
  p.add_argument("--near", type=float, default=1.0, help="m: a floor obstacle this near the chassis centre counts")
  p.add_argument("--out", required=True)
  args = p.parse_args(argv)
  if args.trials < 1 or args.window < 1:
    p.error("--trials and --window: at least 1")
  for run_dir in args.runs:  # before any compilation
    if not all(os.path.exists(os.path.join(run_dir, f)) for f in ("run.json", "policy")):
      p.error(f"{run_dir}: not a run folder with run.json and policy/")
  compile_cache.enable()
  rows = []
  for run_dir in args.runs:
    try:
      flags = rollout(run_dir, args.area, args.trials)
    except (ValueError, ConfigError) as e:
      p.error(f"{run_dir}: {e}")
    hits = collisions(*flags, args.window)
    no_ride = [h for h in hits if not h["riding_in_window"]]
    rows.append({"run": os.path.basename(os.path.normpath(run_dir)), **tally(*flags[:3], args.window),
                 "collided_no_riding_box_near": sum(h["floor_box_m"] is not None and h["floor_box_m"] <= args.near
                                                    for h in no_ride), "collisions": hits})
    print({k: v for k, v in rows[-1].items() if k != "collisions"}, flush=True)
  total = {k: sum(r[k] for r in rows) for k in rows[0] if k not in ("run", "riding_steps_mean", "collisions")}
  print("all", total, flush=True)
  atomic.write_json(args.out, {**provenance(), "area": args.area, "window_steps": args.window, "near_m": args.near,
                               "all": total,
                               "rows": rows})
  return 0


if __name__ == "__main__":
  raise SystemExit(main())

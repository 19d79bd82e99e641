"""The safety filter's view against what happened, step by step, before a trial's first collision.

A run trained or evaluated with control.safety_filter (its own, or the one --set gives it) drives some
of the evaluation's trials of a navigation area again (train.evaluate's trials: the area's draw, reset
keys from EVAL_SEED, eps EVAL_EPS, the exported policy, deterministic). At each of the last steps
before the trial's first collision it lists the policy's command (v m/s, w rad/s), the filter's
(mjx_tracks.envs.safety_filter), the footprint's clearance from the scan's hits and from the walls
themselves (scenes.clearance), the chassis' measured velocity (forward, sideways m/s, yaw rate rad/s:
the filter's other input), whether a belt rides on a floor obstacle (1 or 0), the front and rear
flipper pairs' angles (rad, each pair's mean), and the chassis' motion
over the step in its own frame (dx, dy m, dyaw rad) as the filter predicted it (its command held for
one control period: a unicycle, or with a response time from the measured velocity) and as it was.
Where the two motions part, the filter's prediction, not its sensing, let the collision through.
A trial's path depends on the batch it runs in (the batched program rounds differently): traced with
other trials than the evaluation's, it may collide at another step (trial 78 of ppo-long seed 3: step
36 beside four others, step 56 alone). Prints the rows and writes JSON with the device, command and
date. CPU: about a minute for five trials.

python scripts/analysis/nav_filter_trace.py RUN --trials 49,78 [--area nav/zigzag] [--of 100] [--steps 6] \
    [--set control.safety_filter.KEY=VALUE ...] --out FILE
"""

from __future__ import annotations

import argparse
import os
import sys

import jax
import jax.numpy as jnp
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
from mjx_tracks import atomic, compile_cache  # noqa: E402
from mjx_tracks.sim.pose import chassis_rpy  # noqa: E402
from train.core.policy import act_from_params, load_policy_params  # noqa: E402
from mjx_tracks.envs.config import ConfigError  # noqa: E402
from train.core.run_record import run_config  # noqa: E402
from nav_safety_filter import variants  # noqa: E402  (scripts/analysis/nav_safety_filter.py)
from variants import configured  # noqa: E402  (scripts/analysis/variants.py)
from train.evaluation import EVAL_EPS, EVAL_SEED, EVAL_TRIALS, scene_env, trial_keys, trial_starts  # noqa: E402
from provenance import provenance  # noqa: E402  (scripts/analysis/provenance.py)

COLUMNS = ("v", "w", "filtered_v", "filtered_w", "scan_clearance", "wall_clearance", "x", "y", "yaw",
           "forward", "sideways", "yaw_rate", "on_floor_box", "front_flippers", "rear_flippers")


def step_view(core, s, action) -> jax.Array:
  """(len(COLUMNS),) one trial's view at the start of a step (units in the module docstring)."""
  es, f = s.pipeline_state, core.safety
  m = core._model(es.scene, es.robust)
  v, w, _ = core.controller.decode(action, es.targets, s.info["eps"])
  ranges, measured = core.safety_inputs(m, es)
  points, hit = f.points(ranges)
  v2, w2, _ = f.choose(v, w, ranges, measured)
  pos, yaw = es.data.xpos[core.sim.layout.chassis_body], chassis_rpy(es.data.qpos)[2]
  walls = core.kind.clearance(core.scene, es.scene, pos, yaw, jnp.asarray(f.half, jnp.float32))
  joints = es.data.qpos[core.sim.layout.joint_qpos]
  flippers = [jnp.mean(joints[core.robot.joint_index(g)]) for g in ("front", "rear")]  # rad, each pair's mean
  return jnp.stack([v, w, v2, w2, f.clearance(points, hit, 0.0, 0.0, measured), walls, pos[0], pos[1], yaw, *measured,
                    core.watch.riding(es.data), *flippers])


def trace(run_dir: str, area: str, trials: list[int], of: int, sets: list[str]):
  """(views (steps, trials, COLUMNS), collided (steps, trials), control period s, the filter) of the trials
  (indices into an evaluation of `of` trials: its keys depend on how many it drew), the run's
  config with the filter's overrides `sets` (control.safety_filter.KEY=VALUE; they turn it on)."""
  cfg = run_config(run_dir)
  if sets:
    cfg = configured(cfg.to_dict(), variants([f"set:{';'.join(sets)}"])["set"])
  if not cfg.control.safety_filter.enabled or cfg.randomization.enabled:
    raise SystemExit(f"error: {run_dir}: needs control.safety_filter enabled (the run's, or --set) and no randomization")
  core, draw = scene_env(cfg, area)
  spec, params = load_policy_params(os.path.join(run_dir, "policy"))
  act = act_from_params(spec)(params)
  start = trial_starts(core, trial_keys(of, EVAL_SEED)[np.asarray(trials)], EVAL_EPS, None, draw)

  def body(s, _):
    a = act(s.obs)
    view = jax.vmap(lambda x, y: step_view(core, x, y))(s, a)
    n = jax.vmap(core.step)(s, a)
    return n, (view, n.pipeline_state.collided)
  views, collided = jax.jit(lambda s: jax.lax.scan(body, s, None, length=cfg.episode.max_steps)[1])(start)
  return np.asarray(views), np.asarray(collided), cfg.control.period, core.safety


def motion(f, views: np.ndarray, j: int, period: float) -> tuple[list[float], list[float]]:
  """(predicted by the filter f, actual) motion (dx, dy, dyaw) over step j in the chassis frame at its start."""
  v = dict(zip(COLUMNS, views[j]))
  nxt = dict(zip(COLUMNS, views[j + 1]))
  c, s = np.cos(v["yaw"]), np.sin(v["yaw"])
  dx, dy = nxt["x"] - v["x"], nxt["y"] - v["y"]
  actual = [c * dx + s * dy, -s * dx + c * dy, (nxt["yaw"] - v["yaw"] + np.pi) % (2 * np.pi) - np.pi]
  measured = jnp.asarray([v["forward"], v["sideways"], v["yaw_rate"]], jnp.float32)
  predicted = np.asarray(f.poses(jnp.float32(v["filtered_v"]), jnp.float32(v["filtered_w"]), measured, jnp.array([period])))[0]
  return [round(float(x), 3) for x in predicted], [round(float(x), 3) for x in actual]


def main(argv: list[str] | None = None) -> int:
  p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  p.add_argument("run_dir")
  p.add_argument("--trials", required=True, help="trial indices, comma-separated (e.g. a contacts replay's)")
  p.add_argument("--area", default="nav/zigzag")
  p.add_argument("--of", type=int, default=EVAL_TRIALS, help="trials of the evaluation the indices refer to")
  p.add_argument("--steps", type=int, default=6, help="steps listed up to and including the first collision's")
  p.add_argument("--set", action="append", default=[], help="control.safety_filter.KEY=VALUE (turns the filter on)")
  p.add_argument("--out", required=True)
  args = p.parse_args(argv)
  compile_cache.enable()
  trials = [int(t) for t in args.trials.split(",")]
  if not all(0 <= t < args.of for t in trials):
    p.error(f"--trials: indices from 0 to {args.of - 1}")
  try:
    views, collided, period, f = trace(args.run_dir, args.area, trials, args.of, args.set)
  except (ValueError, ConfigError) as e:
    p.error(str(e))
  out = []
  for k, trial in enumerate(trials):
    hits = np.flatnonzero(collided[:, k])
    rows = []
    for j in range(max(0, int(hits[0]) - args.steps + 1), int(hits[0]) + 1) if hits.size else ():
      predicted, actual = motion(f, views[:, k], j, period)
      rows.append({"step": j, **{c: round(float(x), 3) for c, x in zip(COLUMNS, views[j, k]) if c not in ("x", "y", "yaw")},
                   "predicted_motion": predicted, "actual_motion": actual})
      print(trial, rows[-1], flush=True)
    out.append({"trial": trial, "first_collision_step": int(hits[0]) if hits.size else None, "steps": rows})
  atomic.write_json(args.out, {**provenance(), "run": os.path.basename(os.path.normpath(args.run_dir)),
                               "area": args.area, "set": args.set, "motion": "dx m, dy m, dyaw rad in the chassis frame", "trials": out})
  return 0


if __name__ == "__main__":
  raise SystemExit(main())

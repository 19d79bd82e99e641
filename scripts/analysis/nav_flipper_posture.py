"""How do navigation policies hold their flippers near walls? Each run's policy drives the evaluation's
trials of one navigation area again (train.evaluate's trials: the run's config, the area's draw, reset
keys split from EVAL_SEED, eps EVAL_EPS, the exported policy, deterministic), and every control step
of every trial still running records the mean front and mean rear flipper angle (rad, 0: in line
with the tracks; the limits +-pi/4: either way the flippers' plan-view reach is cos(angle) of their length) and the chassis centre's distance to the nearest wall obstacle
(m, in the plane: its two boxes as rectangles). Prints, per run, the mean angle and |angle| of each
pair over all steps and over the steps within --near m of a wall obstacle, and writes JSON with the device,
command and date. Question it answers: does a policy that must drive over floor boxes (nav-obstacles)
keep its flippers lowered while it turns round a zigzag wall's end, where `nav`'s policies, which
never collide there, hold them otherwise? CPU: about a minute per run.

python scripts/analysis/nav_flipper_posture.py RUN [RUN ...] --area nav/zigzag --near 1.0 \
    --out results/nav/flipper-posture-cpu.json
(run folders with policy/ and run.json: a study's folder that came back, or `git checkout 236240e --
results/studies/nav/runs` for the nav study's first groups)
"""

from __future__ import annotations

import argparse
import os

import jax
import jax.numpy as jnp
import numpy as np

from mjx_tracks import atomic
from scenes.clearance import point_box_distance
from scenes.navigation import WALL_OBSTACLES
from train.core.policy import act_from_params, load_policy_params
from train.core.run_record import run_config
from train.evaluation import EVAL_EPS, EVAL_SEED, scene_env, trial_keys, trial_starts
from provenance import provenance  # scripts/analysis/provenance.py (this script's folder is on sys.path)


def wall_distance(xy: jax.Array, box_pos: jax.Array, box_size: jax.Array) -> jax.Array:
  """() m: the distance from a point to the nearest of the boxes' plane rectangles (0 inside one)."""
  lo, hi = box_pos[:, :2] - box_size[:, :2], box_pos[:, :2] + box_size[:, :2]
  return jnp.min(point_box_distance(xy[None], lo, hi))


def posture_trace(core, act, keys, draw, layout, robot):
  """(steps, trials) arrays: mean front and rear flipper angle (rad), distance to a wall obstacle (m)
  and whether the trial was still running at that step."""
  front, rear = robot.joint_index("front"), robot.joint_index("rear")

  def body(s, _):
    es = s.pipeline_state
    joints = es.data.qpos[:, layout.joint_qpos]
    xy = es.data.xpos[:, layout.chassis_body, :2]
    dist = jax.vmap(wall_distance)(xy, es.scene.box_pos[:, :WALL_OBSTACLES], es.scene.box_size[:, :WALL_OBSTACLES])
    nxt = jax.vmap(core.step)(s, act(s.obs))
    running = s.done == 0
    nxt = nxt.replace(done=jnp.maximum(nxt.done, s.done))  # a finished trial stays finished (no auto-reset here)
    return nxt, (joints[:, front].mean(1), joints[:, rear].mean(1), dist, running)

  s = trial_starts(core, keys, EVAL_EPS, None, draw)
  return jax.lax.scan(body, s, None, length=core.cfg.episode.max_steps)[1]


def posture(run_dir: str, area: str, trials: int, near: float) -> dict:
  """One run's flipper posture on one area's trials."""
  cfg = run_config(run_dir)
  core, draw = scene_env(cfg, area)
  spec, params = load_policy_params(os.path.join(run_dir, "policy"))
  trace = jax.jit(lambda p, k: posture_trace(core, act_from_params(spec)(p), k, draw, core.sim.layout, core.robot))
  front, rear, dist, running = (np.asarray(a) for a in trace(params, trial_keys(trials, EVAL_SEED)))
  close = running & (dist < near)
  mean = lambda x, m: float(x[m].mean()) if m.any() else None  # noqa: E731
  return {"run": run_dir, "task": cfg.task, "area": area, "trials": trials, "steps": int(running.sum()),
          "steps_near_a_wall": int(close.sum()),
          **{f"{name}{suffix}": mean(f(x), m) for name, x in (("front", front), ("rear", rear))
             for suffix, f, m in (("_rad", np.asarray, running), ("_abs_rad", np.abs, running),
                                  ("_rad_near", np.asarray, close), ("_abs_rad_near", np.abs, close))}}


def main(argv: list[str] | None = None) -> int:
  p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  p.add_argument("runs", nargs="+", help="run folders with policy/ and run.json")
  p.add_argument("--area", default="nav/zigzag", help="a navigation area (nav/hallway, nav/zigzag)")
  p.add_argument("--trials", type=int, default=100)
  p.add_argument("--near", type=float, default=1.0, help="m, chassis centre to a wall obstacle")
  p.add_argument("--out", help="JSON path")
  args = p.parse_args(argv)
  rows = []
  for run in args.runs:
    r = posture(run, args.area, args.trials, args.near)
    rows.append(r)
    fmt = lambda x: "-" if x is None else f"{x:.3f}"  # noqa: E731
    print(f"{run} ({r['task']}) {args.area}: mean front {fmt(r['front_rad'])} (|.| {fmt(r['front_abs_rad'])}), rear "
          f"{fmt(r['rear_rad'])} (|.| {fmt(r['rear_abs_rad'])}) rad over {r['steps']} steps; within {args.near} m of a "
          f"wall obstacle ({r['steps_near_a_wall']} steps): front {fmt(r['front_rad_near'])} "
          f"(|.| {fmt(r['front_abs_rad_near'])}), rear {fmt(r['rear_rad_near'])} (|.| {fmt(r['rear_abs_rad_near'])})",
          flush=True)
  if args.out:
    atomic.write_json(args.out, {**provenance(), "area": args.area, "near_m": args.near, "rows": rows})
  return 0


if __name__ == "__main__":
  raise SystemExit(main())

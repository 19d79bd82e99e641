"""What touched what? Each run's policy drives the evaluation's trials of a navigation area again
(the run's config, the area's draw, reset keys split from EVAL_SEED, eps EVAL_EPS, the exported
policy, deterministic: train.evaluate's trials). Beside each control step its physics substeps are
run again one by one from the same state and command (the safety filter's, where the run has one;
the env's _advance without randomization:
tasks with randomization are refused), and the first collision contact of the substep where a
trial's first collision happens names the robot geom and the world geom
(mjx_tracks.sim.collisions). A step the env flags that the replayed substeps do not is counted
as "not found in the substeps" (none is expected). The reports were written
on a GPU and the replay runs here: the same trials, rounded differently, so a trial's course may
part from its report's; each row says how many of the replay's collided trials collided in the
report too (eval-nav-AREA.json), and names each collided trial's first contact by the trial's index.
Prints a line per run and area and writes JSON with the device, command and date. CPU: about 4
minutes per run and area.

python scripts/analysis/nav_collision_contacts.py \
    results/studies/nav/runs/ppo-rings-pen2-goal_nav-obstacles_6000000_s* --areas nav/zigzag \
    --out results/nav/collision-contacts-cpu.json
(the study's run folders with their reports and policies: `git checkout 236240e --
results/studies/nav/runs`, or the study run again)
"""

from __future__ import annotations

import argparse
import collections
import json
import os

import jax
import jax.numpy as jnp
import mujoco
import numpy as np

from mjx_tracks import atomic
from mjx_tracks.sim import mjx_private
from train.core.policy import act_from_params, load_policy_params
from train.core.run_record import run_config
from train.evaluation import EVAL_EPS, EVAL_SEED, report_path, scene_env, trial_keys, trial_starts
from provenance import provenance  # scripts/analysis/provenance.py (this script's folder is on sys.path)

GONE = "not found in the substeps"


def first_collision_pairs(core, make_act, params, keys, draw) -> jax.Array:
  """(trials, 2) int: the geom pair of the first collision contact at the step of each trial's first
  collision (-1, -1 where none was left in the data; -2, -2: no collision)."""
  def body(carry, _):
    s, active, pair = carry
    action = make_act(params)(s.obs)
    nxt = jax.vmap(core.step)(s, action)
    newly = active & nxt.pipeline_state.collided & ~s.pipeline_state.collided
    found = jax.vmap(lambda s1, a: substep_pair(core, s1, a))(s, action)
    return (nxt, active & (nxt.done == 0), jnp.where(newly[:, None], found, pair)), None

  s = trial_starts(core, keys, EVAL_EPS, None, draw)
  trials = len(keys)
  start = (s, jnp.ones(trials, bool), jnp.full((trials, 2), -2, jnp.int32))
  (_, _, pair), _ = jax.lax.scan(body, start, None, length=core.cfg.episode.max_steps)
  return pair


def substep_pair(core, s, action) -> jax.Array:
  """(2,) int: the geom pair of the first collision contact among one control step's substeps, run
  again from state s with the action's command (-1, -1: none)."""
  es = s.pipeline_state
  m = core._model(es.scene, es.robust)
  v, w, targets = core.controller.decode(action, es.targets, s.info["eps"])
  v, w, _ = core._safe_command(m, es, v, w)  # the safety filter's command, where the run has one
  belts = core.controller.belt_speeds(v, w)

  def sub(_, carry):
    x, pair = carry
    x = core.sim.substep(m, x, belts)
    mask = core.watch.colliding(x)
    first = mjx_private.contacts(x).geom[jnp.argmax(mask)]
    return x, jnp.where((pair[0] < 0) & mask.any(), first, pair)
  return jax.lax.fori_loop(0, core.substeps, sub, (es.data.replace(ctrl=targets), jnp.full(2, -1, jnp.int32)))[1]


def pair_name(m: mujoco.MjModel, pair) -> str:
  """'robot geom -> world geom' (names; a nameless geom by its body)."""
  if pair[0] < 0:
    return GONE
  robot, world = sorted(map(int, pair), key=lambda g: m.geom_bodyid[g] == 0)  # the robot's geom first

  def name(g):
    body = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, m.geom_bodyid[g])
    return mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g) or f"geom of {body}"
  return f"{name(robot)} -> {name(world)}"


def contacts(run_dir: str, area: str) -> dict | None:
  """One run's first collision contacts on one area (None where the run has no such report)."""
  path = report_path(run_dir, area, None)
  if not os.path.exists(path):
    return None
  reported = np.asarray(json.load(open(path))["per_trial"]["collided"]) > 0
  cfg = run_config(run_dir)
  if cfg.randomization.enabled:
    raise SystemExit(f"error: {run_dir}: trained with randomization; the substeps are replayed without it")
  core, draw = scene_env(cfg, area)
  spec, params = load_policy_params(os.path.join(run_dir, "policy"))
  run = jax.jit(lambda p, k: first_collision_pairs(core, act_from_params(spec), p, k, draw))
  pairs = np.asarray(run(params, trial_keys(len(reported), EVAL_SEED)))
  collided = pairs[:, 0] != -2
  names = collections.Counter(pair_name(core.sim.mj_model, p) for p in pairs[collided])
  return {"run": run_dir, "area": area, "trials": int(len(reported)), "collided": int(collided.sum()),
          "collided_in_report_too": int((collided & reported).sum()), "report_collided": int(reported.sum()),
          "first_contacts": dict(names.most_common()),
          "per_trial": {int(t): pair_name(core.sim.mj_model, pairs[t]) for t in np.flatnonzero(collided)}}


def main(argv: list[str] | None = None) -> int:
  p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  p.add_argument("runs", nargs="+", help="run folders with policy/ and eval-nav-AREA.json reports")
  p.add_argument("--areas", nargs="+", default=["nav/hallway", "nav/zigzag"], help="navigation areas")
  p.add_argument("--out", help="JSON path")
  args = p.parse_args(argv)
  rows = []
  for run in args.runs:
    for area in args.areas:
      if (r := contacts(run, area)) is not None:
        rows.append(r)
        print(f"{run} {area}: {r['collided']} of {r['trials']} collided ({r['collided_in_report_too']} of them in the "
              f"report's {r['report_collided']} too); first contacts {r['first_contacts']}", flush=True)
  total = dict(sum((collections.Counter(r["first_contacts"]) for r in rows), collections.Counter()).most_common())
  print(f"all: {total}")
  if args.out:
    atomic.write_json(args.out, {**provenance(), "first_contacts_all": total, "rows": rows})
  return 0


if __name__ == "__main__":
  raise SystemExit(main())

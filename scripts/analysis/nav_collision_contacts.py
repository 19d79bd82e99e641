"""What touched what? Each run's policy drives the evaluation's trials of a navigation area again
(the run's config, the area's draw, reset keys split from EVAL_SEED, eps EVAL_EPS, the exported
policy, deterministic: train.evaluate's trials), and at the control step where a trial's first
collision is flagged the collision contacts left in the data (the step's last physics substep:
mjx_tracks.sim.collisions) name the robot geom and the world geom. A collision whose contact ended
before the step's last substep is counted as "gone by the step's end". The reports were written
on a GPU and the replay runs here: the same trials, rounded differently, so a trial's course may
part from its report's; each row says how many of the replay's collided trials collided in the
report too (eval-nav-AREA.json).
Prints a line per run and area and writes JSON with the device, command and date. CPU: about 2
minutes per run and area.

python scripts/analysis/nav_collision_contacts.py \
    results/studies/nav/runs/ppo-rings-pen2-goal_nav-obstacles_6000000_s* --areas nav/zigzag \
    --out results/nav/collision-contacts-cpu.json
"""

from __future__ import annotations

import argparse
import collections
import datetime
import json
import os
import platform
import sys

import jax
import jax.numpy as jnp
import mujoco
import numpy as np

from mjx_tracks import atomic
from mjx_tracks.envs.config import from_dict
from mjx_tracks.envs.task_env import TrackedRobotEnv
from mjx_tracks.sim import mjx_private
from train.core.policy import act_from_params, load_policy_params
from train.core.run_record import read_run_record
from train.evaluation import EVAL_EPS, EVAL_SEED, scene_programs, trial_keys, trial_starts

GONE = "gone by the step's end"


def first_collision_pairs(core, make_act, params, keys, draw) -> jax.Array:
  """(trials, 2) int: the geom pair of the first collision contact at the step of each trial's first
  collision (-1, -1 where none was left in the data; -2, -2: no collision)."""
  def body(carry, _):
    s, active, pair = carry
    nxt = jax.vmap(core.step)(s, make_act(params)(s.obs))
    newly = active & nxt.pipeline_state.collided & ~s.pipeline_state.collided
    mask = jax.vmap(core.watch.colliding)(nxt.pipeline_state.data)  # (trials, contacts)
    geoms = mjx_private.contacts(nxt.pipeline_state.data).geom  # (trials, contacts, 2)
    found = jnp.take_along_axis(geoms, jnp.argmax(mask, axis=1)[:, None, None], axis=1)[:, 0]
    found = jnp.where(mask.any(axis=1)[:, None], found, -1)
    return (nxt, active & (nxt.done == 0), jnp.where(newly[:, None], found, pair)), None

  s = trial_starts(core, keys, EVAL_EPS, None, draw)
  trials = len(keys)
  start = (s, jnp.ones(trials, bool), jnp.full((trials, 2), -2, jnp.int32))
  (_, _, pair), _ = jax.lax.scan(body, start, None, length=core.cfg.episode.max_steps)
  return pair


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
  path = os.path.join(run_dir, f"eval-{area.replace('/', '-')}.json")
  if not os.path.exists(path):
    return None
  reported = np.asarray(json.load(open(path))["per_trial"]["collided"]) > 0
  cfg = from_dict(read_run_record(run_dir)["config"])
  (program, draws), = scene_programs(cfg, [area])
  core = TrackedRobotEnv(program)
  spec, params = load_policy_params(os.path.join(run_dir, "policy"))
  run = jax.jit(lambda p, k: first_collision_pairs(core, act_from_params(spec), p, k, draws[area]))
  pairs = np.asarray(run(params, trial_keys(len(reported), EVAL_SEED)))
  collided = pairs[:, 0] != -2
  names = collections.Counter(pair_name(core.sim.mj_model, p) for p in pairs[collided])
  return {"run": run_dir, "area": area, "trials": int(len(reported)), "collided": int(collided.sum()),
          "collided_in_report_too": int((collided & reported).sum()), "report_collided": int(reported.sum()),
          "first_contacts": dict(names.most_common())}


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
    atomic.write_json(args.out, {"device": f"CPU ({platform.processor() or platform.machine()})",
                                 "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
                                 "command": "python " + " ".join(sys.argv), "jax": jax.__version__,
                                 "first_contacts_all": total, "rows": rows})
  return 0


if __name__ == "__main__":
  raise SystemExit(main())

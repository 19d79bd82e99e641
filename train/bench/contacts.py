"""contacts: how many contacts touch at once, per robot, in every scene kind, against
physics.contact_slots (the contacts MJX keeps per robot and substep, least distance first). Each
task's hardest scene (`uniform` where its kind has none: navigation) is driven with every contact
kept (contact_slots and box_pairs -1), half of the trials at full throttle and half with random
actions (the `full` and `random` baselines), for one episode; a contact touches when the solver
acts on it (distance - margin < 0, mjx_tracks.sim.collisions.penetrating). The figure is sampled at the end of
each control step (the last of its physics substeps). A task passes when its most touching
contacts fit the configured slots; the gate (`python -m train.bench gate`) checks the same against
MuJoCo's C engine along the stair drives.

    python -m train.bench contacts --set physics.contact_slots=24 --trials 8
"""

from __future__ import annotations

import dataclasses

import numpy as np

from train.bench.result import BenchInputError

TRIALS = 32  # per task: the first half at full throttle, the rest random


def add_args(p) -> None:
  from mjx_tracks.tools.rollout_digest import TASKS  # noqa: PLC0415  (each stair direction, terrain kind, nav task)
  p.add_argument("--tasks", nargs="+", default=list(TASKS),
                 help="tasks to drive (default: the rollout digest's, one per stair direction, terrain kind and nav task)")
  p.add_argument("--scene", help="evaluation scene of every task (default: each task's hardest, else uniform)")
  p.add_argument("--trials", type=int, default=TRIALS, help=f"trials per task, even (default {TRIALS})")
  p.add_argument("--set", action="append", default=[], metavar="physics.KEY=VALUE",
                 help="physics settings whose contact_slots the counts are judged against")


def touching_counts(cfg, scene: str, trials: int) -> tuple[np.ndarray, np.ndarray]:
  """(full-throttle trials, random trials): each trial's most touching contacts at the end of a
  control step while its episode lasts, every contact kept, on evaluation scene `scene` of task cfg."""
  import jax  # noqa: PLC0415
  import jax.numpy as jnp  # noqa: PLC0415

  from mjx_tracks.baselines import baseline  # noqa: PLC0415
  from mjx_tracks.sim.collisions import penetrating  # noqa: PLC0415
  from train.evaluation import largest_per_trial  # noqa: PLC0415
  every = dataclasses.replace(cfg, physics=dataclasses.replace(cfg.physics, contact_slots=-1, box_pairs=-1))
  throttle = jnp.arange(trials) < trials // 2

  def make_act(env):
    full, rand = baseline("full").make(env), baseline("random").make(env)
    return lambda s: jnp.where(throttle[:, None], full(s), rand(s))

  def touching(before, after):
    return jax.vmap(lambda d: penetrating(d)[2])(after.pipeline_state.data).sum(-1)
  most = largest_per_trial(every, scene, make_act, touching, trials)
  return most[:trials // 2], most[trials // 2:]


def default_scene(cfg) -> str:
  """The scene the task's in-training probe drives (its hardest where it has one), else uniform."""
  return cfg.scene.probe_scene or "uniform"


def run(args) -> tuple[list[dict], dict]:
  from mjx_tracks.envs.config import ConfigError, load_config  # noqa: PLC0415
  if args.trials < 2 or args.trials % 2:
    raise BenchInputError(f"--trials must be even and at least 2, got {args.trials}")
  if any(not o.startswith("physics.") for o in args.set):
    raise BenchInputError("--set takes physics settings only (physics.KEY=VALUE)")
  from train.evaluation import scene_config  # noqa: PLC0415
  try:
    configs = {task: load_config(task, tuple(args.set)) for task in args.tasks}
    scenes = {task: args.scene or default_scene(cfg) for task, cfg in configs.items()}
    for task, cfg in configs.items():  # every scene checked before anything compiles
      scene_config(cfg, scenes[task])
  except (ConfigError, KeyError, ValueError) as e:
    raise BenchInputError(str(e)) from None
  rows = []
  for task, cfg in configs.items():
    slots, scene = cfg.physics.contact_slots, scenes[task]
    for name, most in zip(("full", "random"), touching_counts(cfg, scene, args.trials)):
      ok = slots < 0 or int(most.max()) <= slots
      rows.append({"task": task, "kind": cfg.scene.kind, "robot": cfg.robot, "baseline": name, "scene": scene,
                   "trials": len(most), "most_touching": int(most.max()), "median_trial_most": float(np.median(most)),
                   "contact_slots": slots, "pass": bool(ok)})
      print(f"{'PASS' if ok else 'FAIL'}  {task} ({cfg.scene.kind}, robot {cfg.robot}), {name}: most touching "
            f"{int(most.max())} (trials' median {np.median(most):g}), slots {slots}", flush=True)
  verdict = all(r["pass"] for r in rows)
  print(f"contacts: {'PASS' if verdict else 'FAIL'} for contact_slots {configs[args.tasks[0]].physics.contact_slots}",
        flush=True)
  return rows, {"overrides": list(args.set), "pass": verdict}

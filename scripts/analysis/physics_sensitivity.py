"""Does a figure depend on the physics settings? Trained policies (or a baseline) drive one
evaluation scene's trials (train.evaluate's: the scene's draw, reset keys from EVAL_SEED, eps
EVAL_EPS, deterministic) under the task's physics as configured and under each --variant of it
(physics.* keys only: the solver's iterations, contact slots, timestep), the same trials under
every setting. Per run (or baseline) and setting: success, progress, tip-overs, time-outs, mean
episode length, collisions (navigation); trial by trial against the configured physics, the successes each setting
gained and lost. A figure that moves with the solver's convergence is the solver's, not the
policy's. Prints a line per row and writes JSON with the device, command and date.

python scripts/analysis/physics_sensitivity.py RUN [RUN ...] --scene hardest+friction-low \
    --variant "NAME:physics.KEY=VALUE;..." [--trials 100] --out FILE
python scripts/analysis/physics_sensitivity.py --baseline scripted --task asc-inc-cog \
    [--set episode.max_steps=200] --scene hardest+friction-low --variant ... --out FILE
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
from mjx_tracks import atomic, compile_cache  # noqa: E402
from mjx_tracks.baselines import BASELINES, baseline  # noqa: E402
from mjx_tracks.envs.config import from_dict, load_config  # noqa: E402
from mjx_tracks.metrics import timed_out  # noqa: E402
from train.core.policy import act_from_params, load_policy_params  # noqa: E402
from train.evaluation import EVAL_EPS, EVAL_SEED, scene_config, trial_runner  # noqa: E402
from variants import configured, parse_variants, shared_config  # noqa: E402  (scripts/analysis/variants.py)
from provenance import provenance  # noqa: E402  (scripts/analysis/provenance.py)

CONFIGURED = "configured"  # the task's physics as the run recorded it (or the baseline's task has it)
PREFIX = "physics."


def variants(specs: list[str]) -> dict[str, list[str]]:
  """{name: overrides} of "NAME:physics.KEY=VALUE;..." specs (ValueError on another key, no key or
  a repeated name)."""
  return parse_variants(specs, PREFIX, CONFIGURED, empty_ok=False)


def outcomes(per_trial: dict) -> dict:
  """Figures and per-trial success of one policy's trials."""
  success = np.asarray(per_trial["success"]) > 0
  return {"success": round(float(success.mean()), 3), "progress": round(float(np.mean(per_trial["progress"])), 3),
          "tipped_over": int((np.asarray(per_trial["tipped_over"]) > 0).sum()),
          "collided": int((np.asarray(per_trial["collided"]) > 0).sum()),
          "timed_out": int(timed_out(per_trial).sum()), "length": round(float(np.mean(per_trial["length"])), 1),
          "per_trial_success": success.astype(int).tolist()}


def paired(base: dict, other: dict) -> dict:
  """Successes a setting gained and lost against the configured physics, trial by trial."""
  a, b = (np.asarray(x["per_trial_success"], bool) for x in (base, other))
  return {"gained": int((~a & b).sum()), "lost": int((a & ~b).sum())}


def policy_runs(args, settings: dict):
  """{setting: [outcomes of each policy]}: the runs' policies as one program per setting, or the baseline."""
  from mjx_tracks.envs.task_env import TrackedRobotEnv  # noqa: PLC0415
  got = {}
  if args.baseline:
    for name, cfg in settings.items():
      act = baseline(args.baseline).make(TrackedRobotEnv(cfg))
      run = trial_runner(cfg, [args.scene], lambda _p, act=act: act, args.trials, EVAL_EPS, EVAL_SEED,
                         observe=lambda s: s)
      got[name] = [outcomes(run(None, args.scene)[0])]
    return got
  loaded = [load_policy_params(os.path.join(r, "policy")) for r in args.runs]
  if any(spec != loaded[0][0] for spec, _ in loaded[1:]):
    raise ValueError("the runs' networks differ; give runs of one group (seeds of one config)")
  for name, cfg in settings.items():  # one program per setting, the policies one after another (their
    # rollouts vmapped over the policies, train.evaluation.group_trial_runner, hung on this 2-core CPU)
    run = trial_runner(cfg, [args.scene], act_from_params(loaded[0][0]), args.trials, EVAL_EPS, EVAL_SEED)
    got[name] = [outcomes(run(params, args.scene)[0]) for _, params in loaded]
  return got


def parse(argv):
  p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  p.add_argument("runs", nargs="*", help="run folders of one group (seeds of one config), each with policy/")
  p.add_argument("--baseline", choices=tuple(BASELINES), help="a baseline on --task instead of runs")
  p.add_argument("--task", help="with --baseline: the task")
  p.add_argument("--set", action="append", default=[], help="with --baseline: a task override (e.g. episode.max_steps=200)")
  p.add_argument("--scene", required=True, help="an evaluation scene, e.g. hardest or hardest+friction-low")
  p.add_argument("--variant", action="append", default=[], required=True, help='"NAME:physics.KEY=VALUE;..." (repeatable)')
  p.add_argument("--trials", type=int, default=100)
  p.add_argument("--out", required=True)
  args = p.parse_args(argv)
  if bool(args.runs) == bool(args.baseline) or bool(args.baseline) != bool(args.task):
    p.error("give run folders, or --baseline NAME with --task TASK")
  if args.set and not args.baseline:
    p.error("--set applies to a baseline's task (a run's task is what it trained on)")
  if args.trials < 1:
    p.error(f"--trials must be at least 1, got {args.trials}")
  return p, args


def main(argv: list[str] | None = None) -> int:
  p, args = parse(argv)
  try:
    named = variants(args.variant)
    raw = (load_config(args.task, tuple(args.set)) if args.baseline else from_dict(shared_config(args.runs))).to_dict()
    settings = {CONFIGURED: from_dict(raw), **{k: configured(raw, v) for k, v in named.items()}}
    for cfg in settings.values():
      scene_config(cfg, args.scene)  # an unknown scene, refused before anything runs
  except (ValueError, FileNotFoundError) as e:  # ConfigError is a ValueError
    p.error(str(e))
  got = policy_runs(args, settings)  # its errors are not the command line's
  names = [f"baseline-{args.baseline}"] if args.baseline else [os.path.basename(os.path.normpath(r)) for r in args.runs]
  rows = []
  for i, who in enumerate(names):
    row = {"policy": who, **{k: v[i] for k, v in got.items()},
           "paired": {k: paired(got[CONFIGURED][i], got[k][i]) for k in named}}
    rows.append(row)
    brief = {k: {m: row[k][m] for m in ("success", "progress", "tipped_over", "collided", "timed_out", "length")}
             for k in settings}
    print(who, args.scene, brief, row["paired"], flush=True)
  means = {k: round(float(np.mean([r[k]["success"] for r in rows])), 3) for k in settings}
  collisions = {k: sum(r[k]["collided"] for r in rows) for k in settings}
  print("mean success:", means, "collisions:", collisions)
  physics = {k: dataclasses.asdict(cfg.physics) for k, cfg in settings.items()}
  atomic.write_json(args.out, {**provenance(), "scene": args.scene, "trials": args.trials, "physics": physics,
                               "mean_success": means, "collisions": collisions, "rows": rows})
  return 0


if __name__ == "__main__":
  compile_cache.enable()
  raise SystemExit(main())

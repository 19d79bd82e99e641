"""Trained navigation policies with and without the safety filter (control.safety_filter), on the
same trials. Each run's exported policy drives the evaluation's trials of each area (train.evaluate's
trials: the area's draw, reset keys from EVAL_SEED, eps EVAL_EPS, deterministic) as the run was
configured, and with the filter enabled under each --variant (default: one, "filter on", with the
settings of configs/defaults.yaml; a variant may turn it off, for runs trained with it). The runs must share one config but for the seed; their policies
run as one program per area and setting. Per run, area and setting: success, collisions, time-outs
(neither reaching the goal, colliding nor tipping over), the fraction of steps the filter acted; and
trial by trial against the run as configured, the collisions each variant removed and the successes
it cost. Prints a line per row and writes JSON with the device, command and date.
On a CPU with jaxlib < 0.11.2, give one run per process: five runs' policies in one program stopped
for good there, 6 tries of 6 (jaxlib's batched LAPACK calls deadlock XLA:CPU's intra-op pool;
results/nav/README.md, 2026-11-28); one ran through.

python scripts/analysis/nav_safety_filter.py RUN [RUN ...] [--areas nav/zigzag,nav/hallway] \
    [--trials 100] [--variant "NAME:control.safety_filter.KEY=VALUE;..." ...] --out FILE
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys

import jax
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
from mjx_tracks import atomic, compile_cache  # noqa: E402
from mjx_tracks.envs.config import from_dict  # noqa: E402
from mjx_tracks.metrics import timed_out  # noqa: E402
from train.core.policy import act_from_params, load_policy_params  # noqa: E402
from train.evaluation import EVAL_EPS, EVAL_SEED, group_trial_runner  # noqa: E402
from provenance import provenance  # noqa: E402  (scripts/analysis/provenance.py)
from variants import configured, parse_variants, shared_config  # noqa: E402  (scripts/analysis/variants.py)

ON = "control.safety_filter.enabled=true"
AS_TRAINED = "as trained"
PREFIX = "control.safety_filter."


def variants(specs: list[str]) -> dict[str, list[str]]:
  """{name: overrides} of "NAME:KEY=VALUE;KEY=VALUE" specs, the filter on in each (default: one,
  "filter on", as configured; ValueError on another key or a repeated name)."""
  parsed = parse_variants(specs or ["filter on:"], PREFIX, AS_TRAINED, empty_ok=True)
  return {name: [ON, *items] for name, items in parsed.items()}


def outcomes(per_trial: dict) -> dict:
  """Counts and per-trial flags of one run's trials."""
  success = np.asarray(per_trial["success"]) > 0
  collided = np.asarray(per_trial["collided"]) > 0
  tipped = np.asarray(per_trial["tipped_over"]) > 0
  return {"success": round(float(success.mean()), 3), "collided": int(collided.sum()),
          "timed_out": int(timed_out(per_trial).sum()), "tipped_over": int(tipped.sum()),
          "filtered_steps": round(float(np.mean(per_trial["filtered"])), 4),
          "per_trial_success": success.astype(int).tolist(), "per_trial_collided": collided.astype(int).tolist()}


def paired(off: dict, on: dict) -> dict:
  """What the filter changed, trial by trial."""
  a = {k: np.asarray(off[f"per_trial_{k}"], bool) for k in ("success", "collided")}
  b = {k: np.asarray(on[f"per_trial_{k}"], bool) for k in ("success", "collided")}
  return {"collisions_removed": int((a["collided"] & ~b["collided"]).sum()),
          "collisions_added": int((~a["collided"] & b["collided"]).sum()),
          "successes_lost": int((a["success"] & ~b["success"]).sum()),
          "successes_gained": int((~a["success"] & b["success"]).sum())}


def main(argv: list[str] | None = None) -> int:
  p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  p.add_argument("runs", nargs="+", help="run folders of one group, each with policy/")
  p.add_argument("--areas", default="nav/zigzag,nav/hallway", help="navigation areas, comma-separated")
  p.add_argument("--trials", type=int, default=100)
  p.add_argument("--variant", action="append", default=[], help='"NAME:control.safety_filter.KEY=VALUE;...", '
                 "a filter setting to compare (repeatable; default: the filter on, as configs/defaults.yaml sets it)")
  p.add_argument("--out", required=True)
  args = p.parse_args(argv)
  try:
    named = variants(args.variant)
    raw = from_dict(shared_config(args.runs)).to_dict()  # with the keys added since they ran (the filter's among them)
    settings = {AS_TRAINED: from_dict(raw), **{k: configured(raw, v) for k, v in named.items()}}
    loaded = [load_policy_params(os.path.join(r, "policy")) for r in args.runs]
  except (ValueError, FileNotFoundError) as e:  # ConfigError is a ValueError
    p.error(str(e))
  compile_cache.enable()
  spec, params = loaded[0][0], jax.tree_util.tree_map(lambda *x: np.stack(x), *(pp for _, pp in loaded))
  rows = []
  for area in args.areas.split(","):
    got = {}
    for name, cfg in settings.items():
      run = group_trial_runner(cfg, area, act_from_params(spec), args.trials, EVAL_EPS, EVAL_SEED)
      got[name] = [outcomes(t) for t in run(params)]
    for i, r in enumerate(args.runs):
      row = {"run": os.path.basename(os.path.normpath(r)), "area": area, **{k: v[i] for k, v in got.items()},
             "paired": {k: paired(got[AS_TRAINED][i], got[k][i]) for k in named}}
      rows.append(row)
      brief = {k: {m: row[k][m] for m in ("success", "collided", "timed_out", "filtered_steps")} for k in settings}
      print(row["run"], area, brief, row["paired"], flush=True)
  totals = {area: {k: {"success_mean": round(float(np.mean([r[k]["success"] for r in rows if r["area"] == area])), 3),
                       **{m: sum(r[k][m] for r in rows if r["area"] == area) for m in ("collided", "timed_out", "tipped_over")}}
                   for k in settings} for area in args.areas.split(",")}
  print(totals)
  filters = {k: dataclasses.asdict(settings[k].control.safety_filter) for k in named}
  atomic.write_json(args.out, {**provenance(), "variants": filters, "trials": args.trials, "totals": totals, "rows": rows})
  return 0


if __name__ == "__main__":
  raise SystemExit(main())

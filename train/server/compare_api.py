"""/api/compare: the evaluations of chosen runs side by side, per scene and budget: the IQM over
the runs with its stratified bootstrap 95 % interval (as the study report, rliable, with 500
resamples instead of 2,000), each run's mean, and beside them the means of the baselines
(mjx_tracks.baselines, `train.evaluate --baseline`) evaluated on the same tasks and scenes."""

from __future__ import annotations

import numpy as np
from fastapi import APIRouter, HTTPException, Query, Request

from mjx_tracks.baselines import ALGO as BASELINE_ALGO
from mjx_tracks.limits import MAX_COMPARE_RUNS
from train.server.deps import db_of, run_or_404
from train.study.statistics import iqm_intervals

router = APIRouter(prefix="/api", tags=["compare"])
METRICS = ("success", "progress", "pitch_rate")  # the figures the compare page shows
REPS = 500  # bootstrap resamples: rliable takes ~0.3 s per figure at the report's 2,000; a page cannot wait that long


@router.get("/compare")
def compare(request: Request, run: list[str] = Query(...)) -> list[dict]:
  """[{scene, budget, runs, per_run: {run: {metric: mean}}, iqm: {metric: [IQM, low, high]},
  baselines: {TASK/NAME: {metric: mean}}}]."""
  if len(run) > MAX_COMPARE_RUNS:
    raise HTTPException(status_code=422, detail=f"compare at most {MAX_COMPARE_RUNS} runs at once, got {len(run)}")
  db = db_of(request)
  per: dict[tuple, dict[str, dict]] = {}
  tasks = {run_or_404(db, run_id)["task"] for run_id in run}
  for run_id in run:
    per.update({k: {**per.get(k, {}), run_id: v} for k, v in _means(db, run_id).items()})
  base = {f"{b['task']}/{b['preset']}": _means(db, b["run_id"]) for b in db.runs()  # TASK/NAME: tasks may differ
          if b["algo"] == BASELINE_ALGO and b["task"] in tasks and b["run_id"] not in run}
  out = []
  for (scene, budget), runs in per.items():
    est = iqm_intervals({m: np.array([v[m] for v in runs.values()]) for m in METRICS}, reps=REPS)
    out.append({"scene": scene, "budget": budget, "runs": len(runs), "per_run": runs,
                "iqm": {m: list(est[m]) for m in METRICS},
                "baselines": {name: m[(scene, None)] for name, m in base.items() if (scene, None) in m}})
  return out


def _means(db, run_id: str) -> dict[tuple, dict[str, float]]:
  """{(scene, budget): {metric: mean over the run's trials}}."""
  return {key: {m: float(np.mean([r[m] for r in rows])) for m in METRICS} for key, rows in db.eval_groups(run_id).items()}

"""/api/launches (queue runs, list the queue, cancel) and the run actions stop / resume / evaluate:
every launch goes to the launcher, which runs it on the Dask cluster."""

from __future__ import annotations

import os

from fastapi import APIRouter, HTTPException, Request
from pydantic import BaseModel

from mjx_tracks.envs.config import ConfigError
from train.core.plan import DEFAULT_LIBRARY
from train.db import ExperimentDB
from train.evaluation import EVAL_TRIALS
from train.server.deps import db_of, run_or_404
from train.server.fields import CriterionText, Name, Overrides, Seed, Steps, Trials, YamlText
from train.server.config_api import config_error
from train.server.launcher import cell_of, stop_run_in, study_of
from train.study.executor import STATE, STUDY_DB, read_cells, status_counts
from train.study.worker import read_pid_file

router = APIRouter(prefix="/api", tags=["launches"])


class LaunchRequest(BaseModel):
  task: Name
  algo: Name = "ppo"
  preset: Name = "cpu"
  steps: Steps = 2048
  seed: Seed = 0
  overrides: Overrides = []  # dotted KEY=VALUE, as `train.run --set`
  hp: Overrides = []  # the preset's hyper-parameters KEY=VALUE, as `train.run --hp`
  library: Name = DEFAULT_LIBRARY  # whose training loop, as `train.run --library`
  early_stop: CriterionText = ""
  eval_trials: Trials = EVAL_TRIALS  # trials per scene of the evaluation suite after training; 0: none
  backend: Name = "cpu"


def _launcher(request: Request):
  launcher = request.app.state.launcher
  if launcher is None:
    raise HTTPException(status_code=503, detail="this server was started without a launcher")
  return launcher


@router.post("/launches", status_code=201)
def launch(body: LaunchRequest, request: Request):
  """Queues a run (checked like a study's runs; 422 names the faulty key)."""
  _launcher(request)
  spec = body.model_dump()
  try:
    cell_of(spec)
  except ConfigError as e:
    return config_error(e)
  return {"id": db_of(request).add_launch("run", spec, None), "status": "queued"}


class StudyRequest(BaseModel):
  yaml: YamlText  # a study file's text, as `python -m train.study FILE` takes it
  overrides: Overrides = []  # top-level KEY=VALUE, as `--set`


@router.post("/studies", status_code=201)
def launch_study(body: StudyRequest, request: Request):
  """Queues a study (validated as `python -m train.study` does; 422 names the faulty key); its runs
  go through the study executor on the launcher's cluster and show up in the run list."""
  _launcher(request)
  spec = body.model_dump()
  try:
    study = study_of(spec)
  except ConfigError as e:
    return config_error(e)
  folder = os.path.join(os.path.abspath(request.app.state.settings.runs_root), "studies", study.name)
  return {"id": db_of(request).add_launch("study", {**spec, "name": study.name}, folder), "status": "queued",
          "folder": folder}


@router.get("/studies")
def studies(request: Request) -> list[dict]:
  """Every study launch with its runs' counts (done / failed / not finished) from its state.json."""
  out = []
  for launch in db_of(request).launches():
    if launch["kind"] == "study":
      folder = launch["out_dir"] or ""
      cells = read_cells(folder) if os.path.exists(os.path.join(folder, STATE)) else {}
      counts = {k: v for k, v in status_counts(cells).items() if k in ("done", "failed")}
      db_path = os.path.join(folder, STUDY_DB)
      run_ids = [r["run_id"] for r in ExperimentDB(db_path).runs()] if os.path.exists(db_path) else []
      out.append({**launch, "runs": len(cells), **counts, "run_ids": run_ids})
  return out


@router.get("/launches")
def launches(request: Request) -> list[dict]:
  """Every launch, oldest first: queued, running and finished."""
  return db_of(request).launches()


@router.delete("/launches/{launch_id}")
def cancel(launch_id: int, request: Request) -> dict:
  """Cancels a queued launch or stops a running one; a finished one is left as it is (200)."""
  try:
    return {"detail": _launcher(request).cancel(launch_id)}
  except KeyError:
    raise HTTPException(status_code=404, detail=f"no launch {launch_id}") from None


@router.post("/runs/{run_id}/stop")
def stop(run_id: str, request: Request) -> dict:
  """SIGTERM to a running run (it checkpoints, exports and ends 'interrupted'); for any other a no-op."""
  run = run_or_404(db_of(request), run_id)
  if run["status"] != "running" and read_pid_file(run["out_dir"]) is None:  # neither training nor evaluating
    return {"detail": f"run {run_id} is {run['status']}; nothing to stop"}
  sent = stop_run_in(db_of(request), run["out_dir"])
  return {"detail": f"run {run_id}: stop requested" if sent else f"run {run_id} runs on another host; not stopped"}


@router.post("/runs/{run_id}/resume", status_code=201)
def resume(run_id: str, request: Request):
  """Queues the run to continue from its last checkpoint (409 while it runs or when it finished)."""
  _launcher(request)
  run = run_or_404(db_of(request), run_id)
  if run["status"] in ("running", "done", "stopped_early"):
    raise HTTPException(status_code=409, detail=f"run {run_id} is {run['status']}; nothing to resume")
  return {"id": db_of(request).add_launch("resume", _spec_of(run), run["out_dir"]), "status": "queued"}


@router.post("/runs/{run_id}/evaluate", status_code=201)
def evaluate(run_id: str, request: Request):
  """Queues the evaluation suite of the run's exported policy."""
  _launcher(request)
  run = run_or_404(db_of(request), run_id)
  return {"id": db_of(request).add_launch("evaluate", _spec_of(run), run["out_dir"]), "status": "queued"}


def _spec_of(run: dict) -> dict:
  """A launch spec for an existing run (its task, algorithm, preset, seed, steps)."""
  return {"task": run["task"], "algo": run["algo"], "preset": run["preset"] or "cpu", "seed": run["seed"] or 0,
          "steps": run["total_steps"] or 1}


@router.get("/studies/{launch_id}/groups")
def study_groups(launch_id: int, request: Request) -> dict:
  """A study's groups as the report has them: per (group, task) the training curves' mean over
  seeds with its 95 % bootstrap band, and per (group, task, budget, scene) the IQM of success and
  progress with its stratified bootstrap interval."""
  from train.study.results import CURVE_METRICS, load_results  # noqa: PLC0415
  from train.study.statistics import curve_band, iqm_intervals  # noqa: PLC0415
  launch = next((l for l in db_of(request).launches() if l["id"] == launch_id and l["kind"] == "study"), None)
  if launch is None:
    raise HTTPException(status_code=404, detail=f"no study launch {launch_id}")
  try:
    results = load_results(launch["out_dir"])
  except FileNotFoundError:
    raise HTTPException(status_code=404, detail=f"study launch {launch_id} has no results yet") from None
  curves = []
  for g in results.spec.groups:
    for task in results.spec.tasks:
      for metric in CURVE_METRICS:
        runs = results.curves(g.name, task, "step", metric)
        if runs:
          x, mean, lo, hi = curve_band(runs)
          curves.append({"group": g.name, "task": task, "metric": metric, "runs": len(runs),
                         "x": x.tolist(), "mean": mean.tolist(), "low": lo.tolist(), "high": hi.tolist()})
  finals = []
  for group, task, budget in results.groups():
    est = iqm_intervals({f"{m} {s}": results.final(group, task, budget, s, m)
                         for s in results.scenes() for m in ("success", "progress")})
    finals.append({"group": group, "task": task, "budget": budget, "iqm": {k: list(v) for k, v in est.items()}})
  return {"name": results.spec.name, "curves": curves, "final": finals}

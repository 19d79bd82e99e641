"""/api/runs: every run of the database with its latest figures, one run's configuration, events,
statistics and evaluations, and its exported policy as a zip."""

from __future__ import annotations

import datetime
import io
import json
import os
import zipfile

from fastapi import APIRouter, HTTPException, Request
from fastapi.responses import FileResponse, StreamingResponse

from mjx_tracks.metrics import EPISODE_NAMES

from train.server.deps import db_of, run_or_404

router = APIRouter(prefix="/api/runs", tags=["runs"])
LIST_FIELDS = ("run_id", "status", "task", "algo", "preset", "seed", "total_steps", "step", "steps_per_s",
               "return_mean", "success_rate", "eps", "started", "ended", "out_dir")


def _duration_s(started: str | None, ended: str | None) -> float | None:
  """Seconds from start to end (or to now, for a run still going)."""
  if not started:
    return None
  t0 = datetime.datetime.fromisoformat(started)
  t1 = datetime.datetime.fromisoformat(ended) if ended else datetime.datetime.now(datetime.timezone.utc)
  return (t1 - t0).total_seconds()


@router.get("")
def list_runs(request: Request) -> list[dict]:
  """Every run: status, task, algorithm, seed, latest step, steps/s, return, success, eps, times."""
  return [{**{k: r.get(k) for k in LIST_FIELDS}, "duration_s": _duration_s(r["started"], r["ended"])}
          for r in db_of(request).summaries()]


@router.get("/{run_id}")
def get_run(run_id: str, request: Request) -> dict:
  """One run: its record, configuration and events."""
  db = db_of(request)
  run = run_or_404(db, run_id)
  config = json.loads(run.pop("config_json") or "{}")
  final = json.loads(run.pop("final_json") or "{}")
  return {**run, "config": config, "final": final, "events": db.events(run_id),
          "duration_s": _duration_s(run["started"], run["ended"])}


@router.get("/{run_id}/stats")
def get_stats(run_id: str, request: Request, source: str | None = None) -> list[dict]:
  """Its statistics rows (source: train | eval | probe; all when not given), by step."""
  db = db_of(request)
  run_or_404(db, run_id)
  rows = db.stats(run_id)
  for r in rows:
    r.pop("metrics_json", None)
  return [r for r in rows if source is None or r["source"] == source]


def _mean(values) -> float | None:
  """The mean of the recorded values; None where none was (a figure added after the trials ran)."""
  kept = [v for v in values if v is not None]
  return sum(kept) / len(kept) if kept else None


@router.get("/{run_id}/evals")
def get_evals(run_id: str, request: Request) -> list[dict]:
  """Its evaluations, one entry per (scene, budget): the mean of each figure and every trial."""
  db = db_of(request)
  run_or_404(db, run_id)
  groups = db.eval_groups(run_id)
  figures = EPISODE_NAMES
  return [{"scene": scene, "budget": budget, "trials": len(rows),
           "mean": {k: _mean(r[k] for r in rows) for k in figures},
           "per_trial": [{k: r[k] for k in ("trial", *figures)} for r in rows]}
          for (scene, budget), rows in groups.items()]


@router.get("/{run_id}/policy")
def download_policy(run_id: str, request: Request) -> StreamingResponse:
  """The exported policy (RUN/policy/) as a zip of its files inside the runs folder (a link out of
  it is left out); 403 if the run lies outside the runs folder."""
  run, settings = run_or_404(db_of(request), run_id), request.app.state.settings
  try:
    folder = settings.inside_runs(os.path.join(run["out_dir"], "policy"))
  except ValueError as e:
    raise HTTPException(status_code=403, detail=f"run {run_id}: {e}") from None
  if not os.path.isdir(folder):
    raise HTTPException(status_code=404, detail=f"run {run_id} has no exported policy yet")
  buf = io.BytesIO()
  with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as z:
    for path in settings.files_below(folder):
      z.write(os.path.realpath(path), os.path.relpath(path, os.path.dirname(folder)))
  buf.seek(0)
  return StreamingResponse(buf, media_type="application/zip",
                           headers={"Content-Disposition": f'attachment; filename="{run_id}-policy.zip"'})


@router.get("/{run_id}/videos")
def list_videos(run_id: str, request: Request) -> list[str]:
  """The rollout videos (MP4) in the run's folder, e.g. from `train.evaluate --video`; none for a
  run outside the runs folder, nor any file that links out of it."""
  run, settings = run_or_404(db_of(request), run_id), request.app.state.settings
  folder = run["out_dir"]
  return sorted(os.path.basename(p) for p in settings.files_below(folder)
                if os.path.dirname(p) == os.path.realpath(folder) and p.endswith(".mp4"))


@router.get("/{run_id}/videos/{name}")
def get_video(run_id: str, name: str, request: Request) -> FileResponse:
  """One of them; 403 for any path that leaves the runs folder, 404 for one that is not there."""
  run = run_or_404(db_of(request), run_id)
  try:
    path = request.app.state.settings.inside_runs(os.path.join(run["out_dir"], name))
  except ValueError as e:
    raise HTTPException(status_code=403, detail=f"run {run_id}: {e}") from None
  if not name.endswith(".mp4") or not os.path.isfile(path):
    raise HTTPException(status_code=404, detail=f"run {run_id} has no video {name[:80]!r}")
  return FileResponse(path, media_type="video/mp4")

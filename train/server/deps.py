"""What every API route needs of a request: the server's database, a run of it (or 404)."""

from __future__ import annotations

from fastapi import HTTPException, Request

from train.db import ExperimentDB


def db_of(request: Request) -> ExperimentDB:
  return ExperimentDB(request.app.state.settings.db)


def run_or_404(db: ExperimentDB, run_id: str) -> dict:
  """The run's record; HTTP 404 naming it if the database has no such run."""
  try:
    return db.run(run_id)
  except KeyError:
    raise HTTPException(status_code=404, detail=f"no run {run_id!r}") from None

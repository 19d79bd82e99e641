"""/api/tasks, /api/trainers and /api/validate: the tasks, the algorithms with their presets and the
training libraries (train.core), and a configuration checked by the loader the command line uses
(configs/defaults.yaml <- the task's YAML <- overrides); errors name their field."""

from __future__ import annotations

from fastapi import APIRouter
from fastapi.responses import JSONResponse
from pydantic import BaseModel

from mjx_tracks.envs.config import ConfigError, available_tasks, load_config
from train.server.fields import Name, Overrides

router = APIRouter(prefix="/api", tags=["configuration"])


class ConfigRequest(BaseModel):
  task: Name
  overrides: Overrides = []  # dotted KEY=VALUE, as `train.run --set`


def config_error(e: ConfigError) -> JSONResponse:
  """HTTP 422 in FastAPI's own shape, its `loc` naming the configuration key."""
  loc = ["body", "task"] if e.key == "task" else ["body", "overrides", e.key or ""]
  return JSONResponse(status_code=422, content={"detail": [{"loc": loc, "msg": str(e), "type": "config"}]})


@router.get("/tasks")
def tasks() -> list[str]:
  return available_tasks()


@router.get("/trainers")
def trainers() -> dict:
  """{algos: {algo: [preset, ...]} (the default library's), library_algos: {library: {algo: [preset,
  ...]}}, libraries: {name: what it trains with}, default_library}: the form's choices, from
  train.core's presets and libraries."""
  from train.core.plan import DEFAULT_LIBRARY, LIBRARIES  # noqa: PLC0415
  from train.core.presets import presets_of  # noqa: PLC0415
  per = {lib: {a: list(p) for a, p in presets_of(lib).items()} for lib in LIBRARIES}
  return {"algos": per[DEFAULT_LIBRARY], "library_algos": per, "libraries": LIBRARIES, "default_library": DEFAULT_LIBRARY}


@router.get("/schema/{task}")
def task_schema(task: str):
  """The form's fields: every key by section with its kind, default for this task and note."""
  from train.server.schema import schema  # noqa: PLC0415
  try:
    return schema(task)
  except ConfigError as e:
    return config_error(e)


@router.post("/validate")
def validate(body: ConfigRequest):
  """The whole configuration the task and overrides give, or 422 naming the faulty key."""
  try:
    return {"task": body.task, "config": load_config(body.task, tuple(body.overrides)).to_dict()}
  except ConfigError as e:
    return config_error(e)

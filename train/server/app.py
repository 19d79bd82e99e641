"""The FastAPI application: the API routers over one database and runs folder, behind the guard
(train.server.guard); the OpenAPI schema at /openapi.json, read by the offline /docs page."""

from __future__ import annotations

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse

from train.server import compare_api, config_api, launches_api, pages, runs_api
from train.server.guard import Guard
from train.server.settings import Settings


def create_app(settings: Settings, launcher=None) -> FastAPI:
  """The app; launcher (train.server.launcher.Launcher, started by the caller) runs its launches."""
  app = FastAPI(title="mjx-tracks", description="Runs, studies and evaluations of mjx-tracks.",
                docs_url=None, redoc_url=None)  # FastAPI's pages load Swagger / ReDoc from a CDN
  app.add_middleware(Guard, token=settings.token)
  app.state.settings, app.state.launcher = settings, launcher
  app.add_exception_handler(RequestValidationError, _invalid)
  app.include_router(runs_api.router)
  app.include_router(config_api.router)
  app.include_router(launches_api.router)
  app.include_router(compare_api.router)
  app.include_router(pages.router)
  return app


async def _invalid(_: Request, exc: RequestValidationError) -> JSONResponse:
  """FastAPI's 422, less the `input` it echoes (unbounded: the whole offending value)."""
  detail = [{k: e[k] for k in ("loc", "msg", "type") if k in e} for e in exc.errors()[:20]]
  return JSONResponse(status_code=422, content={"detail": detail})

"""The FastAPI application: the API routers over one database and runs folder (OpenAPI at /docs)."""

from __future__ import annotations

from fastapi import FastAPI

from train.server import compare_api, config_api, launches_api, pages, runs_api
from train.server.settings import Settings


def create_app(settings: Settings, launcher=None) -> FastAPI:
  """The app; launcher (train.server.launcher.Launcher, started by the caller) runs its launches."""
  app = FastAPI(title="mjx-tracks", description="Runs, studies and evaluations of mjx-tracks.")
  app.state.settings, app.state.launcher = settings, launcher
  app.include_router(runs_api.router)
  app.include_router(config_api.router)
  app.include_router(launches_api.router)
  app.include_router(compare_api.router)
  app.include_router(pages.router)
  return app

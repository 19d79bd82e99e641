"""The FastAPI application: the API routers over one database and runs folder (OpenAPI at /docs)."""

from __future__ import annotations

from fastapi import FastAPI

from train.server import config_api, runs_api
from train.server.settings import Settings


def create_app(settings: Settings) -> FastAPI:
  app = FastAPI(title="mjx-tracks", description="Runs, studies and evaluations of mjx-tracks.")
  app.state.settings = settings
  app.include_router(runs_api.router)
  app.include_router(config_api.router)
  return app

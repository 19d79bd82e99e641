"""The dashboard: pages (HTML + JavaScript that polls the API, charts by plotly.js served from the
installed plotly package, nothing from the internet) and their static files."""

from __future__ import annotations

import os
import pathlib

import plotly
from fastapi import APIRouter, HTTPException
from fastapi.responses import FileResponse, HTMLResponse

STATIC = pathlib.Path(__file__).with_name("static")
PLOTLY_JS = pathlib.Path(plotly.__file__).parent / "package_data" / "plotly.min.js"
PAGES = {"/": "runs.html", "/new": "new.html", "/queue": "queue.html", "/compare": "compare.html",
         "/docs": "docs.html"}  # the token is checked by the guard (train.server.guard)
ASSETS = {"common.js": STATIC / "common.js", "style.css": STATIC / "style.css", "plotly.min.js": PLOTLY_JS}

router = APIRouter(include_in_schema=False)


def _page(name: str):
  def serve() -> HTMLResponse:
    return HTMLResponse((STATIC / name).read_text())
  return serve


for _path, _name in PAGES.items():
  router.add_api_route(_path, _page(_name), methods=["GET"])
router.add_api_route("/runs/{run_id}", _page("run.html"), methods=["GET"])


@router.get("/static/{name}")
def asset(name: str) -> FileResponse:
  """The pages' scripts and style (no data in them: the guard serves them without the token)."""
  if name not in ASSETS or not os.path.exists(ASSETS[name]):
    raise HTTPException(status_code=404, detail=f"no asset {name!r}")
  return FileResponse(ASSETS[name])

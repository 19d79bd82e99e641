"""`python -m train.server [--db PATH] [--runs DIR] [--host 127.0.0.1] [--port 8000] [--token T]`:
serves the API (docs at /docs) with uvicorn. Listening beyond this machine needs a token
(--token or $MJX_TRACKS_TOKEN); every request must then carry it."""

from __future__ import annotations

import argparse
import os
import sys

from train.db import DEFAULT_ROOT, default_path
from train.server.auth import TOKEN_ENV, check_bind
from train.server.settings import Settings


def main(argv: list[str] | None = None) -> int:
  p = argparse.ArgumentParser(prog="python -m train.server", description=__doc__.splitlines()[0])
  p.add_argument("--db", help="experiment database (default: runs/experiments.sqlite)")
  p.add_argument("--runs", default=DEFAULT_ROOT, help="the runs folder: files are served from below it only")
  p.add_argument("--host", default="127.0.0.1")
  p.add_argument("--port", type=int, default=8000)
  p.add_argument("--token", default=os.environ.get(TOKEN_ENV), help=f"access token (default ${TOKEN_ENV})")
  args = p.parse_args(argv)
  try:
    check_bind(args.host, args.token)
  except ValueError as e:
    print(f"error: {e}", file=sys.stderr)
    return 2
  import uvicorn  # noqa: PLC0415

  from train.server.app import create_app  # noqa: PLC0415
  app = create_app(Settings(args.db or default_path(args.runs), args.runs, args.token))
  uvicorn.run(app, host=args.host, port=args.port, log_level="info")
  return 0


if __name__ == "__main__":
  sys.exit(main())

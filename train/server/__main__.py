"""`python -m train.server [--db PATH] [--runs DIR] [--host 127.0.0.1] [--port 8000] [--token T]`:
serves the API (docs at /docs) with uvicorn, and runs its launches on a Dask cluster (started here:
a worker per GPU and CPU slots, or --scheduler). Listening beyond this machine needs a token
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
  p.add_argument("--scheduler", metavar="tcp://HOST:8786", help="run launches on an existing Dask cluster")
  p.add_argument("--gpus", help="local GPUs for launches, e.g. 0,1 (default: all)")
  p.add_argument("--slots-per-gpu", type=int, default=1)
  p.add_argument("--cpu-slots", type=int, help="runs at once on the CPU backend (default: 1 without GPUs, else 0)")
  args = p.parse_args(argv)
  try:
    check_bind(args.host, args.token)
  except ValueError as e:
    print(f"error: {e}", file=sys.stderr)
    return 2
  import uvicorn  # noqa: PLC0415

  from train.server.app import create_app  # noqa: PLC0415
  from train.server.launcher import Launcher  # noqa: PLC0415
  from train.study.cluster import make_client  # noqa: PLC0415
  settings = Settings(args.db or default_path(args.runs), args.runs, args.token)
  try:
    client, kinds = make_client(args.scheduler, args.gpus, args.slots_per_gpu, args.cpu_slots)
  except (ValueError, OSError) as e:
    print(f"error: {e}", file=sys.stderr)
    return 2
  launcher = Launcher(settings.db, settings.runs_root, client, kinds).start()
  try:
    uvicorn.run(create_app(settings, launcher), host=args.host, port=args.port, log_level="info")
  finally:
    launcher.stop()
    client.close()
  return 0


if __name__ == "__main__":
  sys.exit(main())

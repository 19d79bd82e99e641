"""`python -m train.server [--db PATH] [--runs DIR] [--host 127.0.0.1] [--port 8000] [--token-file F]`:
serves the dashboard and the API (docs at /docs) with uvicorn, and runs its launches on a Dask
cluster (started here on loopback with TLS: a worker per GPU and CPU slots; or --scheduler).
Listening beyond this machine needs a token (--token-file or $MJX_TRACKS_TOKEN); every request must
then carry it. The README's server section states the threat model."""

from __future__ import annotations

import argparse
import sys

from train.db import DEFAULT_ROOT, default_path
from train.server.auth import TOKEN_ENV, check_bind, read_token
from train.server.settings import Settings
from train.study.cluster import add_cluster_args


def main(argv: list[str] | None = None) -> int:
  p = argparse.ArgumentParser(prog="python -m train.server", description=__doc__.splitlines()[0])
  p.add_argument("--db", help="experiment database (default: runs/experiments.sqlite)")
  p.add_argument("--runs", default=DEFAULT_ROOT, help="the runs folder: files are served from below it only")
  p.add_argument("--host", default="127.0.0.1")
  p.add_argument("--port", type=int, default=8000)
  p.add_argument("--token-file", metavar="FILE", help=f"the access token, first line of FILE (mode 600); default "
                 f"${TOKEN_ENV}; none: loopback only, without a token")
  p.add_argument("--token", help=argparse.SUPPRESS)  # refused: a token on the command line shows in ps
  add_cluster_args(p)
  args = p.parse_args(argv)
  if args.token is not None:
    print(f"error: --token would show the token to every user of this machine (ps, /proc); put it in a file "
          f"(chmod 600) and pass --token-file FILE, or set ${TOKEN_ENV}", file=sys.stderr)
    return 2
  if not 1 <= args.port <= 65535:
    print(f"error: --port must be from 1 to 65535, got {args.port}", file=sys.stderr)
    return 2
  try:
    token = read_token(args.token_file)
    check_bind(args.host, token)
  except ValueError as e:
    print(f"error: {e}", file=sys.stderr)
    return 2
  import uvicorn  # noqa: PLC0415

  from train.server.app import create_app  # noqa: PLC0415
  from train.server.launcher import Launcher  # noqa: PLC0415
  from train.study.cluster import make_client  # noqa: PLC0415
  settings = Settings(args.db or default_path(args.runs), args.runs, token)
  try:
    client, kinds = make_client(args)
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

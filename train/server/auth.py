"""The server's access token: with one set, every request must carry it (header
`Authorization: Bearer TOKEN`, or `?token=TOKEN` for links and downloads); without, none does."""

from __future__ import annotations

import hmac

from fastapi import HTTPException, Request

TOKEN_ENV = "MJX_TRACKS_TOKEN"  # the environment variable `python -m train.server` reads the token from
LOOPBACK = ("127.0.0.1", "localhost", "::1")  # addresses that may be served without a token


def given_token(request: Request) -> str | None:
  header = request.headers.get("authorization", "")
  if header.lower().startswith("bearer "):
    return header[7:].strip()
  return request.query_params.get("token")


def check_token(request: Request) -> None:
  """401 unless the request carries the app's token (when it has one)."""
  want = request.app.state.settings.token
  if want and not hmac.compare_digest((given_token(request) or "").encode(), want.encode()):
    raise HTTPException(status_code=401, detail="a valid token is required (Authorization: Bearer TOKEN)")


def check_bind(host: str, token: str | None) -> None:
  """ValueError when the server would listen beyond this machine without a token."""
  if host not in LOOPBACK and not token:
    raise ValueError(f"listening on {host} needs a token: --token TOKEN or ${TOKEN_ENV}")

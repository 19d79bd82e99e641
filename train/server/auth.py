"""The server's access token. With one set, every request but the pages' static assets and the
login form must carry it: header `Authorization: Bearer TOKEN` (scripts), or the HttpOnly,
SameSite=Strict cookie that the login form (or a first link with `?token=TOKEN`, answered by a
redirect that drops it from the address) sets for the browser. Without a token the server
listens on loopback only and answers only requests that name it by a loopback address."""

from __future__ import annotations

import hmac
import http.cookies
import os

from train.study.cluster import LOOPBACK  # the addresses that stay on this machine (one definition)

TOKEN_ENV = "MJX_TRACKS_TOKEN"  # the environment variable `python -m train.server` reads the token from
COOKIE = "mjx_tracks_token"  # the browser's copy of the token
MIN_TOKEN_CHARS = 16  # shorter tokens are refused at start (guessable)


def token_matches(given: str | None, want: str) -> bool:
  return given is not None and hmac.compare_digest(given.encode("utf-8", "replace"), want.encode())


def header_or_cookie_token(headers: dict[str, str]) -> str | None:
  """The token a request carries: its bearer header, else its cookie (headers: lower-case names)."""
  auth = headers.get("authorization", "")
  if auth.lower().startswith("bearer "):
    return auth[7:].strip()
  jar = http.cookies.SimpleCookie()
  try:
    jar.load(headers.get("cookie", ""))
  except http.cookies.CookieError:
    return None
  return jar[COOKIE].value if COOKIE in jar else None


def cookie_header(token: str) -> str:
  return f"{COOKIE}={token}; HttpOnly; SameSite=Strict; Path=/"


def read_token(token_file: str | None) -> str | None:
  """The token from --token-file (its first line) or $MJX_TRACKS_TOKEN; ValueError if the file is
  unreadable, empty or short, or readable by other users."""
  if token_file is None:
    token = os.environ.get(TOKEN_ENV) or None
  else:
    try:
      mode = os.stat(token_file).st_mode
      with open(token_file) as f:
        token = f.readline().strip()
    except OSError as e:
      raise ValueError(f"--token-file: {e.strerror}: {token_file}") from None
    if mode & 0o077:
      raise ValueError(f"--token-file {token_file} is readable by other users: chmod 600 it")
  if token is not None and len(token) < MIN_TOKEN_CHARS:
    raise ValueError(f"the token must have at least {MIN_TOKEN_CHARS} characters (e.g. openssl rand -hex 16)")
  return token


def check_bind(host: str, token: str | None) -> None:
  """ValueError when the server would listen beyond this machine without a token."""
  if host not in LOOPBACK and not token:
    raise ValueError(f"listening on {host} needs a token: --token-file FILE or ${TOKEN_ENV}")

"""The server's front door, an ASGI middleware that runs before any route reads a request:
- the token (train.server.auth), checked before the body is read; a `?token=` in the address is
  taken out of the request (so the access log never shows it) and answered by a redirect that sets
  the cookie;
- without a token, requests must name the server by a loopback address (no DNS rebinding);
- state-changing requests (POST, PUT, PATCH, DELETE) from a browser must come from the server's own
  pages (Origin / Referer of the same host): no cross-site form posts;
- bodies of at most MAX_BODY_BYTES, JSON nested at most as deep as Python parses, valid Unicode."""

from __future__ import annotations

import json
import pathlib
import urllib.parse

from mjx_tracks.limits import MAX_BODY_BYTES
from train.server.auth import cookie_header, header_or_cookie_token, token_matches
from train.study.cluster import LOOPBACK

UNSAFE = {"POST", "PUT", "PATCH", "DELETE"}
PUBLIC = ("/static/",)  # the pages' scripts and style: no data in them
LOGIN = "/login"
LOGIN_PAGE = pathlib.Path(__file__).with_name("static") / "login.html"


async def _answer(send, status: int, body: bytes, content_type: str, extra: list | None = None) -> None:
  headers = [(b"content-type", content_type.encode()), (b"content-length", str(len(body)).encode()), *(extra or [])]
  await send({"type": "http.response.start", "status": status, "headers": headers})
  await send({"type": "http.response.body", "body": body})


async def _error(send, status: int, detail: str) -> None:
  await _answer(send, status, json.dumps({"detail": detail}).encode(), "application/json")


def _pop_query_token(scope: dict) -> str | None:
  """Removes `token=` from the request's query string, in place (the access log reads it later)."""
  pairs = urllib.parse.parse_qsl(scope.get("query_string", b"").decode("latin-1"), keep_blank_values=True)
  tokens = [v for k, v in pairs if k == "token"]
  if tokens:
    scope["query_string"] = urllib.parse.urlencode([(k, v) for k, v in pairs if k != "token"]).encode()
  return tokens[-1] if tokens else None


def _host_name(host: str) -> str:
  return urllib.parse.urlsplit(f"//{host}").hostname or ""


def _cross_site(method: str, headers: dict) -> bool:
  """A state-changing browser request whose Origin (or Referer) is not this server's host."""
  if method not in UNSAFE:
    return False
  source = headers.get("origin") or headers.get("referer")
  if not source:
    return False  # not a browser (browsers send Origin on every cross-site POST)
  return source == "null" or urllib.parse.urlsplit(source).netloc != headers.get("host", "")


def _bad_json(body: bytes) -> str | None:
  """Why a JSON body cannot be taken (too deep, not Unicode text), or None (including bodies that
  do not parse: the route says why)."""
  try:
    value = json.loads(body)
  except RecursionError:
    return "the JSON body is nested too deeply"
  except ValueError:
    return None
  stack = [value]
  while stack:
    x = stack.pop()
    if isinstance(x, str):
      try:
        x.encode("utf-8")
      except UnicodeEncodeError:
        return "the JSON body holds text that is not valid Unicode (a lone surrogate)"
    elif isinstance(x, dict):
      stack += [*x.keys(), *x.values()]
    elif isinstance(x, list):
      stack += x
  return None


class Guard:
  def __init__(self, app, token: str | None):
    self.app, self.token = app, token

  async def __call__(self, scope, receive, send):
    if scope["type"] != "http":
      return await self.app(scope, receive, send)
    headers = {k.decode("latin-1").lower(): v.decode("latin-1") for k, v in scope["headers"]}
    query_token, method, path = _pop_query_token(scope), scope["method"], scope["path"]
    if not self.token and _host_name(headers.get("host", "")) not in LOOPBACK:
      return await _error(send, 403, "this server answers only requests to a loopback address")
    if _cross_site(method, headers):
      return await _error(send, 403, "cross-site request refused")
    if self.token and not path.startswith(PUBLIC):
      if path == LOGIN:
        return await self._login(scope, receive, send, headers)
      if method == "GET" and token_matches(query_token, self.token):
        return await self._redirect(send, path, scope["query_string"], self.token)
      if not token_matches(header_or_cookie_token(headers), self.token):
        return await self._refuse(send, method, path)
    body = await self._body(receive, headers, send) if method in UNSAFE else b""
    if body is None:
      return None
    if body and "json" in headers.get("content-type", "") and (why := _bad_json(body)):
      return await _error(send, 422, why)
    return await self.app(scope, _replay(body, receive) if method in UNSAFE else receive, send)

  async def _body(self, receive, headers: dict, send) -> bytes | None:
    """The whole body, or None once a 413 was sent for one over MAX_BODY_BYTES."""
    length = headers.get("content-length", "0")
    if not length.isdigit() or int(length) > MAX_BODY_BYTES:
      await _error(send, 413, f"the request body is over {MAX_BODY_BYTES:,} bytes")
      return None
    chunks, size, more = [], 0, True
    while more:
      message = await receive()
      if message["type"] == "http.disconnect":
        return None
      chunks.append(message.get("body", b""))
      size += len(chunks[-1])
      more = message.get("more_body", False)
      if size > MAX_BODY_BYTES:
        await _error(send, 413, f"the request body is over {MAX_BODY_BYTES:,} bytes")
        return None
    return b"".join(chunks)

  async def _redirect(self, send, path: str, query: bytes, token: str) -> None:
    location = path + (f"?{query.decode('latin-1')}" if query else "")
    await _answer(send, 303, b"", "text/plain", [(b"location", location.encode("latin-1")),
                                                 (b"set-cookie", cookie_header(token).encode())])

  async def _refuse(self, send, method: str, path: str) -> None:
    if method == "GET" and not path.startswith("/api") and path != "/openapi.json":
      return await _answer(send, 401, LOGIN_PAGE.read_bytes(), "text/html; charset=utf-8")
    return await _error(send, 401, "a valid token is required (Authorization: Bearer TOKEN, or log in at /login)")

  async def _login(self, scope, receive, send, headers: dict) -> None:
    """GET: the form; POST (form field `token`): the cookie and a redirect to the runs, or 401."""
    if scope["method"] != "POST":
      return await _answer(send, 200, LOGIN_PAGE.read_bytes(), "text/html; charset=utf-8")
    body = await self._body(receive, headers, send)
    if body is None:
      return None
    given = urllib.parse.parse_qs(body.decode("latin-1")).get("token", [None])[-1]
    if not token_matches(given, self.token):
      return await _answer(send, 401, LOGIN_PAGE.read_bytes(), "text/html; charset=utf-8")
    return await self._redirect(send, "/", b"", self.token)


def _replay(body: bytes, receive):
  """A receive() that hands the app the body already read, then waits on the real one."""
  sent = False

  async def replay():
    nonlocal sent
    if not sent:
      sent = True
      return {"type": "http.request", "body": body, "more_body": False}
    return await receive()

  return replay

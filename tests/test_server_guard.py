"""The server's front door (train.server.guard) and its inputs, probed as an attacker would, on
loopback: the token (header, cookie, never in a logged address), the documentation behind it and
offline, no cross-site posts or foreign Host names without a token, bounded bodies and fields,
files only from inside the runs folder, and every bad request a 4xx naming what is wrong."""

import logging
import os
import time

import httpx
import pytest
from fastapi.testclient import TestClient

from train.db import ExperimentDB
from train.server.app import create_app
from train.server.auth import COOKIE, read_token
from train.server.background import serve_in_thread
from train.server.settings import Settings

LOCAL = "http://127.0.0.1"
TOKEN = "0123456789abcdef-secret"


@pytest.fixture()
def settings(tmp_path):
  root = tmp_path / "runs"
  (root / "a" / "policy").mkdir(parents=True)
  (root / "a" / "policy" / "policy.json").write_text('{"step": 1}')
  (root / "a" / "roll.mp4").write_bytes(b"\x00")
  outside = tmp_path / "secret"
  outside.mkdir()
  (outside / "key.txt").write_text("private")
  (outside / "other.mp4").write_bytes(b"\x00")
  os.symlink(outside / "key.txt", root / "a" / "policy" / "key.txt")  # links out of the runs folder
  os.symlink(outside / "other.mp4", root / "a" / "other.mp4")
  db = ExperimentDB(str(root / "experiments.sqlite"))
  db.start("a", "asc-inc-cog", "ppo", "cpu", 0, {"task": "asc-inc-cog"}, str(root / "a"), 300)
  db.start("b", "asc-inc-cog", "ppo", "cpu", 0, {}, str(outside), 300)
  return Settings(str(root / "experiments.sqlite"), str(root))


def _client(settings, token=None, **kw) -> TestClient:
  return TestClient(create_app(Settings(settings.db, settings.runs_root, token)), base_url=LOCAL, **kw)


def test_the_token_is_a_header_or_an_httponly_cookie_and_a_link_token_becomes_the_cookie(settings):
  client = _client(settings, TOKEN, follow_redirects=False)
  assert client.get("/api/runs").status_code == 401
  assert client.get("/api/runs", headers={"Authorization": f"Bearer {TOKEN}"}).status_code == 200
  page = client.get("/")
  assert page.status_code == 401 and 'action="/login"' in page.text  # a page asks for the token
  r = client.get("/runs/a", params={"token": TOKEN, "x": "1"})
  assert r.status_code == 303 and r.headers["location"] == "/runs/a?x=1"  # the token leaves the address
  cookie = r.headers["set-cookie"]
  assert cookie.startswith(f"{COOKIE}={TOKEN}") and "HttpOnly" in cookie and "SameSite=Strict" in cookie
  assert client.get("/api/runs").status_code == 200  # the client now holds the cookie
  other = _client(settings, TOKEN, follow_redirects=False)
  assert other.post("/login", data={"token": "wrong"}).status_code == 401
  assert other.post("/login", data={"token": TOKEN}).status_code == 303
  assert other.get("/api/runs").status_code == 200


def test_the_documentation_and_schema_need_the_token(settings):
  client = _client(settings, TOKEN)
  for path in ("/docs", "/openapi.json", "/redoc"):
    assert client.get(path).status_code == 401, path
  assert client.get("/static/common.js").status_code == 200  # no data in it
  auth = {"Authorization": f"Bearer {TOKEN}"}
  assert client.get("/openapi.json", headers=auth).status_code == 200
  assert client.get("/redoc", headers=auth).status_code == 404  # ReDoc loads from a CDN: not served


def test_a_token_in_an_address_never_reaches_the_access_log(settings):
  lines = []
  handler = logging.Handler()
  handler.emit = lambda record: lines.append(record.getMessage())
  url, stop = serve_in_thread(create_app(Settings(settings.db, settings.runs_root, TOKEN)), log_level="info")
  logging.getLogger("uvicorn.access").addHandler(handler)
  try:
    r = httpx.get(f"{url}/api/runs?token={TOKEN}&a=1", follow_redirects=False)
    assert r.status_code == 303
    httpx.get(f"{url}/api/runs", headers={"Authorization": f"Bearer {TOKEN}"})
    time.sleep(0.2)
  finally:
    logging.getLogger("uvicorn.access").removeHandler(handler)
    stop()
  assert len(lines) >= 2 and "/api/runs?a=1" in " ".join(lines)
  assert not any(TOKEN in line for line in lines), lines


def test_the_token_comes_from_a_private_file_or_the_environment_never_the_command_line(tmp_path, monkeypatch, capsys):
  from train.server.__main__ import main as server_main
  path = tmp_path / "token"
  path.write_text(TOKEN + "\n")
  os.chmod(path, 0o600)
  assert read_token(str(path)) == TOKEN
  os.chmod(path, 0o644)
  with pytest.raises(ValueError, match="readable by other users"):
    read_token(str(path))
  monkeypatch.setenv("MJX_TRACKS_TOKEN", "short")
  with pytest.raises(ValueError, match="at least 16"):
    read_token(None)
  assert server_main(["--token", TOKEN]) == 2
  assert "--token-file" in capsys.readouterr().err
  assert server_main(["--port", "99999"]) == 2 and "--port must be" in capsys.readouterr().err


def test_without_a_token_only_loopback_names_and_same_site_posts_are_answered(settings):
  client = _client(settings)
  assert client.get("/api/runs").status_code == 200
  rebound = TestClient(create_app(settings), base_url="http://evil.example:8000")  # DNS rebinding
  assert rebound.get("/api/runs").status_code == 403
  forged = client.post("/api/runs/a/evaluate", headers={"Origin": "http://evil.example"})
  assert forged.status_code == 403 and "cross-site" in forged.json()["detail"]
  assert client.post("/api/runs/a/evaluate", headers={"Referer": "http://evil.example/x"}).status_code == 403
  same = client.post("/api/validate", json={"task": "asc-inc-cog"}, headers={"Origin": LOCAL})
  assert same.status_code == 200


def test_bodies_are_bounded_and_not_read_before_the_token_is_checked(settings):
  client = _client(settings, TOKEN)
  assert client.post("/api/validate", content=b"{not json").status_code == 401  # never parsed
  auth = {"Authorization": f"Bearer {TOKEN}", "Content-Type": "application/json"}
  big = client.post("/api/validate", content=b" " * (2 << 20), headers=auth)
  assert big.status_code == 413


@pytest.mark.parametrize("body, phrase", [
    ('{"task": "asc-inc-cog", "overrides": ' + "[" * 100_000 + "]" * 100_000 + "}", "nested too deeply"),
    ('{"task": "\\ud800"}', "not valid Unicode"),
])
def test_hostile_json_is_refused_in_one_line(settings, body, phrase):
  r = _client(settings).post("/api/validate", content=body.encode(), headers={"Content-Type": "application/json"})
  assert r.status_code == 422 and phrase in r.json()["detail"]


def _bomb(levels: int) -> str:
  """A YAML alias bomb: 9 ** levels leaves from a few hundred bytes."""
  lines = ["l0: &l0 [x, x, x, x, x, x, x, x, x]"]
  lines += [f"l{i}: &l{i} [" + ", ".join([f"*l{i - 1}"] * 9) + "]" for i in range(1, levels + 1)]
  return "\n".join(lines)


def test_yaml_bombs_and_huge_or_malformed_values_are_refused_fast_with_short_messages(settings):
  client = _client(settings)
  t = time.time()
  r = client.post("/api/validate", json={"task": "asc-inc-cog", "overrides": [f"scene.tread={{{_bomb(7)}}}"]})
  assert r.status_code == 422 and len(r.content) < 2_000, r.content[:300]
  r = client.post("/api/studies", json={"yaml": _bomb(8)})
  assert r.status_code in (422, 503) and len(r.content) < 2_000
  assert time.time() - t < 5
  for item in ("scene.tread=[0.3", "scene.tread=" + "x" * 5_000):
    r = client.post("/api/validate", json={"task": "asc-inc-cog", "overrides": [item]})
    assert r.status_code == 422 and len(r.content) < 2_000


def test_numeric_fields_names_and_run_counts_are_bounded(settings, monkeypatch):
  client = _client(settings)
  for field, value in (("eval_trials", 10**9), ("steps", 10**30), ("seed", -1), ("task", "x" * 300)):
    r = client.post("/api/launches", json={"task": "asc-inc-cog", field: value})
    assert r.status_code == 422 and r.json()["detail"][0]["loc"][-1] == field, (field, r.json())
  from train.server import compare_api
  # refused before any run is looked up (was: within 2 s, a timing that a loaded machine can miss)
  monkeypatch.setattr(compare_api, "db_of", lambda request: pytest.fail("the 3,000 runs were looked up"))
  r = client.get("/api/compare", params=[("run", "a")] * 3_000)
  assert r.status_code == 422 and "at most" in r.json()["detail"]


def test_files_are_served_only_from_inside_the_runs_folder_and_errors_name_no_path(settings, tmp_path):
  import io
  import zipfile
  client = _client(settings)
  names = zipfile.ZipFile(io.BytesIO(client.get("/api/runs/a/policy").content)).namelist()
  assert names == ["policy/policy.json"]  # the link out of the folder is left out
  assert client.get("/api/runs/a/videos").json() == ["roll.mp4"]
  assert client.get("/api/runs/b/videos").json() == []  # a run outside the runs folder
  for path in ("/api/runs/a/videos/other.mp4", "/api/runs/b/policy"):
    r = client.get(path)
    assert r.status_code == 403 and str(tmp_path) not in r.text, r.text


@pytest.mark.parametrize("yaml_text, phrase", [
    ("- a\n- list", "top level must be a mapping"),
    ("name: " + "[" * 5_000 + "]" * 5_000, "nested too deeply"),
    ("name: " + "x" * 300 + "\ntasks: [asc-inc-cog]\nseeds: [0]\ngroups: [{name: g, algo: ppo, preset: cpu, steps: [1]}]",
     "at most 64 characters"),
    ('name: "t\\n"\ntasks: [asc-inc-cog]\nseeds: [0]\ngroups: [{name: g, algo: ppo, preset: cpu, steps: [1]}]',
     "not a plain name"),
])
def test_bad_studies_through_the_api_are_422_naming_the_fault(settings, yaml_text, phrase):
  client = TestClient(create_app(settings, launcher=object()), base_url=LOCAL)  # refused before any queueing
  r = client.post("/api/studies", json={"yaml": yaml_text})
  assert r.status_code == 422 and phrase in r.json()["detail"][0]["msg"], r.json()
  assert client.get("/api/launches").json() == []

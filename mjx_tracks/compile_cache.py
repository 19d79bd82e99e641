"""JAX's persistent compilation cache, outside any checkout: $MJX_TRACKS_CACHE, else
~/.cache/mjx_tracks/jax. A second run on the same machine skips most compilation."""

from __future__ import annotations

import json
import os
import pathlib

from mjx_tracks import atomic


def cache_dir() -> pathlib.Path:
  return pathlib.Path(os.environ.get("MJX_TRACKS_CACHE") or pathlib.Path.home() / ".cache" / "mjx_tracks" / "jax")


def enable() -> pathlib.Path:
  """Turns the persistent cache on for every compilation over 1 s, keyed by each program's content
  however this process's tracing shared its functions (mjx_tracks.jax_private), and (unless
  MJX_TRACKS_COMPILE_LOCK=0) makes the processes sharing it compile each program once: one waits
  while another compiles a program it needs, then loads it; returns its directory."""
  import jax  # noqa: PLC0415
  from mjx_tracks import jax_private  # noqa: PLC0415
  path = cache_dir()
  path.mkdir(parents=True, exist_ok=True)
  jax.config.update("jax_compilation_cache_dir", str(path))
  jax.config.update("jax_persistent_cache_min_compile_time_secs", 1.0)
  jax.config.update("jax_persistent_cache_min_entry_size_bytes", 0)
  jax_private.key_programs_by_content()
  if os.environ.get("MJX_TRACKS_COMPILE_LOCK", "1") != "0":
    jax_private.serialize_compilations(str(path / "locks"))
  if os.environ.get("MJX_TRACKS_COMPILE_LOG"):
    log_compilations(os.environ["MJX_TRACKS_COMPILE_LOG"])
  return path


_COMPILE_EVENTS = ("Finished ", "Persistent compilation cache hit", "PERSISTENT COMPILATION CACHE MISS", "Waited ")


def log_compilations(path: str) -> None:
  """Appends every XLA compilation (seconds) and persistent-cache hit or miss of this process to
  `path`, one line each with the pid and the pytest test running (its env var reaches the
  subprocesses a test starts): where a test suite's time goes ($MJX_TRACKS_COMPILE_LOG)."""
  import logging  # noqa: PLC0415

  class _Events(logging.Handler):
    def emit(self, record: logging.LogRecord) -> None:
      msg = record.getMessage()
      if msg.startswith(_COMPILE_EVENTS):
        test = os.environ.get("PYTEST_CURRENT_TEST", "-").split(" ")[0]
        with open(path, "a") as f:
          f.write(f"{os.getpid()}\t{test}\t{msg[:200]}\n")

  for name in ("jax._src.dispatch", "jax._src.compiler", "mjx_tracks.jax_private"):
    logger = logging.getLogger(name)
    if not any(type(h).__name__ == "_Events" for h in logger.handlers):
      logger.setLevel(logging.DEBUG)
      logger.addHandler(_Events(logging.DEBUG))


def longest_compilations(path: str, n: int = 10) -> list[list]:
  """The n longest XLA compilations [seconds, what] logged in `path` by log_compilations ([] where
  there is no such file)."""
  import re  # noqa: PLC0415
  rows = []
  for line in open(path, errors="replace") if os.path.exists(path) else ():
    m = re.search(r"Finished XLA compilation of (\S+) in ([0-9.e-]+) sec", line)
    if m:
      rows.append([round(float(m.group(2)), 2), m.group(1)])
  return sorted(rows, reverse=True)[:n]


def _times_path() -> pathlib.Path:
  return cache_dir() / "compile_seconds.json"


def last_compile_seconds(what: str) -> float | None:
  """The longest `what` (e.g. 'ppo/gpu/4096 envs on cuda') took to compile here, if known: a cold
  compilation, which is what a run must be ready for (a warm cache only makes it shorter)."""
  try:
    return float(json.loads(_times_path().read_text())[what])
  except (OSError, ValueError, KeyError, TypeError):
    return None


def record_compile_seconds(what: str, seconds: float) -> None:
  """Remembers a compilation time if it is the longest yet (for the next run's estimate: a partial
  cache hit must not teach a short one); never fails the caller."""
  try:
    path = _times_path()
    times = json.loads(path.read_text()) if path.exists() else {}
    times[what] = round(max(seconds, float(times.get(what, 0.0))), 1)
    atomic.write_json(path, times)
  except (OSError, ValueError):
    pass

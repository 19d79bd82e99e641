"""JAX's persistent compilation cache, outside any checkout: $MJX_TRACKS_CACHE, else
~/.cache/mjx_tracks/jax. A second run on the same machine skips most compilation."""

from __future__ import annotations

import os
import pathlib


def cache_dir() -> pathlib.Path:
  return pathlib.Path(os.environ.get("MJX_TRACKS_CACHE") or pathlib.Path.home() / ".cache" / "mjx_tracks" / "jax")


def enable() -> pathlib.Path:
  """Turns the persistent cache on for every compilation over 1 s; returns its directory."""
  import jax  # noqa: PLC0415
  path = cache_dir()
  path.mkdir(parents=True, exist_ok=True)
  jax.config.update("jax_compilation_cache_dir", str(path))
  jax.config.update("jax_persistent_cache_min_compile_time_secs", 1.0)
  jax.config.update("jax_persistent_cache_min_entry_size_bytes", 0)
  return path

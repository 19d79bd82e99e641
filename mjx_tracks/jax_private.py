"""JAX's private compiler API, used in this one module (MJX's is in mjx_tracks.sim.mjx_private):
a hook that makes the processes of one machine compile each program once. jax 0.10-0.11:
`jax._src.compiler._compile_and_write_cache` (called on a persistent-cache miss, with the cache key)
and `jax._src.compiler._cache_read` (0.11 added its `host_callbacks`); tests/test_compile_lock.py
fails where an upgrade changes them. Where they are not as expected, nothing is hooked."""

from __future__ import annotations

import fcntl
import hashlib
import inspect
import logging
import os
import time

logger = logging.getLogger("mjx_tracks.compile_lock")
_MARK = "_mjx_tracks_compile_lock"  # set on the hook, so that installing it twice wraps once
# the hooked function's parameters (what compile_or_get_cached passes it), and those _cache_read may take
COMPILE_AND_WRITE = ("backend", "computation", "executable_devices", "compile_options", "host_callbacks",
                     "module_name", "cache_key")
CACHE_READ = ("module_name", "cache_key", "compile_options", "backend", "executable_devices", "host_callbacks")


def _api():
  """(jax._src.compiler, the names _cache_read takes), or None where either function is missing or
  takes other parameters than this module knows."""
  from jax._src import compiler  # noqa: PLC0415
  hooked, read = getattr(compiler, "_compile_and_write_cache", None), getattr(compiler, "_cache_read", None)
  if hooked is None or read is None:
    return None
  if tuple(inspect.signature(inspect.unwrap(hooked)).parameters) != COMPILE_AND_WRITE:
    return None
  takes = tuple(inspect.signature(read).parameters)
  return (compiler, takes) if set(takes) <= set(CACHE_READ) else None


def installed() -> bool:
  """Whether serialize_compilations' hook is in place in this process."""
  from jax._src import compiler  # noqa: PLC0415
  return getattr(getattr(compiler, "_compile_and_write_cache", None), _MARK, False)


def hookable() -> bool:
  """Whether this JAX has the private API serialize_compilations hooks, as it expects it."""
  return _api() is not None


def serialize_compilations(lock_dir: str) -> None:
  """From now on in this process: a program that missed the persistent compilation cache is
  compiled under a file lock named by its cache key (in lock_dir). A process that needs a program
  another process is compiling waits for it, then loads it from the cache (where JAX stored it:
  programs that took over jax_persistent_cache_min_compile_time_secs), instead of compiling it a
  second time beside it. The kernel drops the lock of a process that dies."""
  if installed():
    return
  api = _api()
  if api is None:  # another JAX: compile as it does
    logger.warning("this JAX's private compiler API is not the one mjx_tracks.jax_private knows: processes "
                   "may compile a program twice at once")
    return
  compiler, read_takes = api
  compile_and_write = compiler._compile_and_write_cache  # noqa: SLF001
  os.makedirs(lock_dir, exist_ok=True)

  def locked(backend, computation, executable_devices, compile_options, host_callbacks, module_name, cache_key):
    given = dict(backend=backend, executable_devices=executable_devices, compile_options=compile_options,
                 host_callbacks=host_callbacks, module_name=module_name, cache_key=cache_key)
    name = hashlib.sha256(cache_key.encode()).hexdigest()[:32] + ".lock"
    with open(os.path.join(lock_dir, name), "w") as lock:
      t0 = time.monotonic()
      fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes
      waited = time.monotonic() - t0
      # another process may have stored the program since this one missed it (while this one waited,
      # or just before it asked)
      executable, _ = compiler._cache_read(**{k: given[k] for k in read_takes})  # noqa: SLF001
      if waited > 0.1:
        logger.debug("Waited %.1f s for another process compiling %s (%s)", waited, module_name,
                     "loaded from the cache" if executable is not None else "compiling it here")
      if executable is not None:
        return executable
      return compile_and_write(backend, computation, executable_devices, compile_options, host_callbacks,
                               module_name, cache_key)

  setattr(locked, _MARK, True)
  compiler._compile_and_write_cache = locked  # noqa: SLF001

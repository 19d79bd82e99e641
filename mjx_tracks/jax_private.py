"""JAX's private compiler API, used in this one module (MJX's is in mjx_tracks.sim.mjx_private):
a hook that makes the processes of one machine compile each program once. jax 0.10-0.11:
`jax._src.compiler._compile_and_write_cache` (called on a persistent-cache miss, with the cache key)
and `jax._src.compiler._cache_read`; tests/test_compile_lock.py fails where an upgrade changes them."""

from __future__ import annotations

import fcntl
import hashlib
import logging
import os
import time

logger = logging.getLogger("mjx_tracks.compile_lock")
_MARK = "_mjx_tracks_compile_lock"  # set on the hook, so that installing it twice wraps once


def installed() -> bool:
  """Whether serialize_compilations' hook is in place in this process."""
  from jax._src import compiler  # noqa: PLC0415
  return getattr(getattr(compiler, "_compile_and_write_cache", None), _MARK, False)


def serialize_compilations(lock_dir: str) -> None:
  """From now on in this process: a program that missed the persistent compilation cache is
  compiled under a file lock named by its cache key (in lock_dir). A process that needs a program
  another process is compiling waits for it, then loads it from the cache (where JAX stored it:
  programs that took over jax_persistent_cache_min_compile_time_secs), instead of compiling it a
  second time beside it. The kernel drops the lock of a process that dies."""
  from jax._src import compiler  # noqa: PLC0415

  compile_and_write = getattr(compiler, "_compile_and_write_cache", None)
  if compile_and_write is None or not hasattr(compiler, "_cache_read"):  # another JAX: compile as it does
    logger.warning("this JAX has no jax._src.compiler._compile_and_write_cache: processes may compile a "
                   "program twice at once")
    return
  if getattr(compile_and_write, _MARK, False):
    return
  os.makedirs(lock_dir, exist_ok=True)

  def locked(backend, computation, executable_devices, compile_options, host_callbacks, module_name, cache_key):
    name = hashlib.sha256(cache_key.encode()).hexdigest()[:32] + ".lock"
    with open(os.path.join(lock_dir, name), "w") as lock:
      t0 = time.monotonic()
      fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes
      waited = time.monotonic() - t0
      # another process may have stored the program since this one missed it (while this one waited,
      # or just before it asked)
      executable, _ = compiler._cache_read(module_name, cache_key, compile_options, backend,  # noqa: SLF001
                                           executable_devices)
      if waited > 0.1:
        logger.debug("Waited %.1f s for another process compiling %s (%s)", waited, module_name,
                     "loaded from the cache" if executable is not None else "compiling it here")
      if executable is not None:
        return executable
      return compile_and_write(backend, computation, executable_devices, compile_options, host_callbacks,
                               module_name, cache_key)

  setattr(locked, _MARK, True)
  compiler._compile_and_write_cache = locked  # noqa: SLF001

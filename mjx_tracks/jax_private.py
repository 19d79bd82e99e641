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

logger = logging.getLogger("mjx_tracks.jax_private")
WAIT_POLL_S = 0.1  # s between tries of a lock another process holds
WAIT_NOTE_S = 30.0  # s of waiting after which a warning says for what
WAIT_MAX_S = 1_800.0  # s after which a process stops waiting and compiles the program itself
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
  if tuple(inspect.signature(inspect.unwrap(hooked)).parameters) != COMPILE_AND_WRITE:  # unwrap: the hook's original
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


def _acquire(path: str, module_name: str):
  """The open lock file at path, locked (after waiting for the process holding it, at most
  WAIT_MAX_S), with the seconds waited; (None, s) where it cannot be locked (a filesystem without
  flock, a file of another user, no space) or the wait ran out: then the caller compiles unlocked."""
  t0 = time.monotonic()
  try:
    lock = open(path, "a")
  except OSError:
    return None, 0.0
  noted = False
  while True:
    try:
      fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)  # released when the file closes
      return lock, time.monotonic() - t0
    except BlockingIOError:
      waited = time.monotonic() - t0
      if waited > WAIT_MAX_S:
        break
      if waited > WAIT_NOTE_S and not noted:
        noted = True
        logger.warning("waiting for another process compiling %s (%s) to finish, up to %.0f s", module_name,
                       path, WAIT_MAX_S)
      time.sleep(WAIT_POLL_S)
    except OSError:
      break
  lock.close()
  return None, time.monotonic() - t0


def serialize_compilations(lock_dir: str) -> None:
  """From now on in this process: a program that missed the persistent compilation cache is
  compiled under a file lock named by its cache key (in lock_dir). A process that needs a program
  another process is compiling waits for it, then loads it from the cache where JAX stored it
  (programs that took over jax_persistent_cache_min_compile_time_secs and call back to no host
  function), else compiles it itself. The kernel drops the lock of a process that dies. Processes of
  one multi-process run (jax.distributed) compile as JAX does: only process 0 stores programs."""
  if installed():
    return
  api = _api()
  if api is None:  # another JAX: compile as it does
    logger.warning("this JAX's private compiler API is not the one mjx_tracks.jax_private knows: processes "
                   "may compile a program twice at once")
    return
  try:
    os.makedirs(lock_dir, exist_ok=True)
  except OSError as e:
    logger.warning("no compile locks (%s): processes may compile a program twice at once", e)
    return
  compiler, read_takes = api
  compile_and_write = compiler._compile_and_write_cache  # noqa: SLF001

  def locked(backend, computation, executable_devices, compile_options, host_callbacks, module_name, cache_key):
    args = (backend, computation, executable_devices, compile_options, host_callbacks, module_name, cache_key)
    import jax  # noqa: PLC0415
    if jax.process_count() > 1:
      return compile_and_write(*args)
    lock, waited = _acquire(os.path.join(lock_dir, hashlib.sha256(cache_key.encode()).hexdigest()[:32] + ".lock"),
                            module_name)
    try:
      # another process may have stored the program since this one missed it (while this one waited,
      # or just before it asked)
      given = dict(zip(COMPILE_AND_WRITE, args))
      executable, _ = compiler._cache_read(**{k: given[k] for k in read_takes})  # noqa: SLF001
      if waited > 0.1:
        logger.debug("Waited %.1f s for another process compiling %s (%s)", waited, module_name,
                     "loaded from the cache" if executable is not None else "compiling it here")
      return executable if executable is not None else compile_and_write(*args)
    finally:
      if lock is not None:
        lock.close()

  setattr(locked, _MARK, True)
  locked.__wrapped__ = compile_and_write  # what _api checks
  compiler._compile_and_write_cache = locked  # noqa: SLF001

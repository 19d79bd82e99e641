"""JAX's private compiler API, used in this one module (MJX's is in mjx_tracks.sim.mjx_private):
- a hook that makes the processes of one machine compile each program once. jax 0.10-0.11:
  `jax._src.compiler._compile_and_write_cache` (called on a persistent-cache miss, with the cache
  key) and `jax._src.compiler._cache_read` (0.11 added its `host_callbacks`);
- persistent-cache keys made from a program's content: `jax._src.cache_key._hash_computation`.
tests/test_compile_lock.py and tests/test_cache_key.py fail where an upgrade changes them. Where they
are not as expected, nothing is hooked."""

from __future__ import annotations

import fcntl
import hashlib
import inspect
import logging
import os
import re
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


# The persistent cache's key hashes a program's MLIR. A function called from several places in it is
# one private function or several equal ones, and their names carry counters: both follow from what
# JAX's trace caches (of bounded size) held when the program was traced, so the same program traced
# after other programs, in another process or later in the same one, can get another key and be
# compiled again (tests/test_env.py's Gymnasium step, after 5 other tasks' programs, 2026-11-29).
# key_programs_by_content hashes each private function by its body instead of its name, callees
# first: equal programs get one key however their functions were shared.
HASH_COMPUTATION = ("hash_obj", "module")  # _hash_computation's first two parameters
# its third parameter (jax 0.10: ignore_callbacks, an IgnoreCallbacks; 0.11: ignore_custom_partitioning),
# and its value where the module is hashed as it is (the only case hashed by content)
CALLBACK_PARAMS = {"ignore_callbacks": "NO", "ignore_custom_partitioning": False}
_KEY_MARK = "_mjx_tracks_content_key"
_NAME = r'(?:"(?:[^"\\]|\\.)*"|[\w$.\-]+)'  # a symbol's name as MLIR prints it: bare, or quoted (@"<lambda>")
_FUNC = re.compile(rf"^  func\.func (?:(?:public|private|nested) )?@({_NAME})")
_SYMBOL = re.compile(rf"@({_NAME})")
KEY_FORMAT = b"mjx_tracks content key 1\n"  # a new format never meets keys of the old one


def program_content(text: str) -> bytes:
  """A program's MLIR text (no debug info) as hashed for its cache key: the lines outside functions;
  `main` with every call of a function replaced by the hash of that function's body, in which its
  own calls are replaced the same way (names of functions dropped); and the set of every function's
  hash (one called from nowhere included: nothing of the text is left out)."""
  bodies, outside, name, lines = {}, [], None, []
  for line in text.split("\n"):
    head = _FUNC.match(line) if name is None else None
    if head:
      name, lines = head.group(1), [_FUNC.sub("  func.func @", line, count=1)]
    elif name is not None:
      lines.append(line)
      if line == "  }":  # the function's end, at its own indentation
        bodies[name], name = "\n".join(lines), None
    else:
      outside.append(line)
  if "main" not in bodies or name is not None:
    raise ValueError("not a module with a main function as jax lowers it")
  digests: dict[str, str] = {}

  def digest(fn: str) -> str:
    if fn not in digests:
      body = _SYMBOL.sub(lambda m: digest(m.group(1)) if m.group(1) in bodies else m.group(0), bodies[fn])
      digests[fn] = "@" + hashlib.sha256(body.encode()).hexdigest()
    return digests[fn]
  every = "\n".join(sorted({digest(fn) for fn in bodies}))
  return KEY_FORMAT + "\n".join([*outside, digest("main"), every]).encode()


def _key_api():
  """(jax._src.cache_key, the name of _hash_computation's third parameter), or None where it is not
  as this module knows it."""
  from jax._src import cache_key  # noqa: PLC0415
  fn = getattr(cache_key, "_hash_computation", None)
  if fn is None:
    return None
  params = tuple(inspect.signature(inspect.unwrap(fn)).parameters)
  known = params[:2] == HASH_COMPUTATION and len(params) == 3 and params[2] in CALLBACK_PARAMS
  return (cache_key, params[2]) if known else None


def as_is(cache_key, third: str):
  """The value of _hash_computation's third parameter (named `third`) with which JAX hashes the
  module as it is: the one case key_programs_by_content hashes by content."""
  value = CALLBACK_PARAMS[third]
  return getattr(cache_key.IgnoreCallbacks, value) if isinstance(value, str) else value


def computation_key(module, by_content: bool = True) -> str:
  """The computation's part of a persistent-cache key of `module` (an MLIR module as JAX lowers it),
  hex: by content (key_programs_by_content's hook, which must be in place) or JAX's own hash."""
  api = _key_api()
  if api is None:
    raise RuntimeError("this JAX's private cache-key API is not the one mjx_tracks.jax_private knows")
  cache_key, third = api
  if by_content and not keys_by_content():
    raise RuntimeError("keys by content are not switched on (key_programs_by_content)")
  fn = cache_key._hash_computation  # noqa: SLF001
  fn = fn if by_content else getattr(fn, "__wrapped__", fn)
  h = hashlib.sha256()
  fn(h, module, as_is(cache_key, third))
  return h.hexdigest()


def keys_by_content() -> bool:
  """Whether key_programs_by_content's hook is in place in this process."""
  from jax._src import cache_key  # noqa: PLC0415
  return getattr(getattr(cache_key, "_hash_computation", None), _KEY_MARK, False)


def key_programs_by_content() -> None:
  """From now on in this process: a program's persistent-cache key hashes program_content(its MLIR
  text) where JAX would hash its MLIR bytecode (not where the key is to keep metadata, or where
  callbacks or custom partitioning are left out of it: JAX's own hash then)."""
  if keys_by_content():
    return
  api = _key_api()
  if api is None:
    logger.warning("this JAX's private cache-key API is not the one mjx_tracks.jax_private knows: equal "
                   "programs traced in other orders may be compiled again")
    return
  cache_key, third = api
  original, plain = cache_key._hash_computation, as_is(cache_key, third)  # noqa: SLF001
  import jax  # noqa: PLC0415

  def hashed(hash_obj, module, flag):
    if flag != plain or jax.config.jax_compilation_cache_include_metadata_in_key:
      return original(hash_obj, module, flag)
    try:
      content = program_content(module.operation.get_asm(enable_debug_info=False))
    except ValueError:  # not laid out as this module reads it
      return original(hash_obj, module, flag)
    hash_obj.update(content)

  setattr(hashed, _KEY_MARK, True)
  hashed.__wrapped__ = original
  cache_key._hash_computation = hashed  # noqa: SLF001

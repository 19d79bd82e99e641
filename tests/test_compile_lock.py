"""Two processes that need the same program at once compile it once (mjx_tracks.jax_private,
switched on by compile_cache.enable): the second waits on the first's lock, then loads the program
from the persistent cache. Also fails where a JAX upgrade moves the private compiler API it hooks."""

import inspect
import os
import subprocess
import sys
import time

from mjx_tracks import jax_private

# A process that compiles one program under the lock, with the persistent cache storing every program;
# it writes ROLE-compiling when XLA starts compiling that program, and the role "first" then holds
# (inside the lock) until the file "go" exists.
WORKER = """
import os, sys, time
role, folder, nonce = sys.argv[1], sys.argv[2], float(sys.argv[3])
import jax, jax.numpy as jnp
from jax._src import compiler
from mjx_tracks import compile_cache
compile_cache.enable()
jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
real = compiler.backend_compile_and_load
def compiling(backend, module, *args, **kwargs):
  if "lambda" in str(module.operation.attributes["sym_name"]):  # not the small programs around it
    open(os.path.join(folder, role + "-compiling"), "w").close()
    while role == "first" and not os.path.exists(os.path.join(folder, "go")):
      time.sleep(0.02)
  return real(backend, module, *args, **kwargs)
compiler.backend_compile_and_load = compiling
out = jax.jit(lambda x: jnp.sin(x) * nonce + jnp.cos(x)).lower(jax.ShapeDtypeStruct((5,), jnp.float32)).compile()
print("ran", float(out(jnp.ones(5, jnp.float32))[0]))
"""


def _wait(predicate, what: str, timeout_s: float = 60.0) -> None:
  t_end = time.time() + timeout_s
  while not predicate():
    assert time.time() < t_end, f"no {what} within {timeout_s} s"
    time.sleep(0.02)


def test_the_hook_is_installed_on_the_private_api_it_expects():
  """The private functions as mjx_tracks.jax_private knows them (jax 0.10: _cache_read without
  host_callbacks; 0.11: with), and the call on a cache miss that it hooks."""
  from jax._src import compiler
  assert jax_private.hookable()
  # installed by tests/conftest.py's compile_cache.enable(), unless the suite runs with it off
  assert jax_private.installed() == (os.environ.get("MJX_TRACKS_COMPILE_LOCK", "1") != "0")
  read = list(inspect.signature(compiler._cache_read).parameters)
  assert read in (list(jax_private.CACHE_READ[:5]), list(jax_private.CACHE_READ)), read
  assert "_compile_and_write_cache(" in inspect.getsource(compiler.compile_or_get_cached)


def test_a_program_two_processes_need_at_once_is_compiled_by_one(tmp_path):
  folder, log = str(tmp_path), str(tmp_path / "compile.log")
  env = {k: v for k, v in os.environ.items() if k != "MJX_TRACKS_COMPILE_LOCK"}
  env.update(MJX_TRACKS_CACHE=str(tmp_path / "cache"), MJX_TRACKS_COMPILE_LOG=log, JAX_PLATFORMS="cpu")

  def start(role):
    return subprocess.Popen([sys.executable, "-c", WORKER, role, folder, "1.25"], env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True)
  first = start("first")
  procs = [first]
  try:
    _wait(lambda: os.path.exists(os.path.join(folder, "first-compiling")), "compilation in the first process")
    second = start("second")
    procs.append(second)
    missed = lambda: os.path.exists(log) and any(  # noqa: E731
        line.startswith(f"{second.pid}\t") and "CACHE MISS for 'jit__lambda'" in line for line in open(log))
    _wait(missed, "cache miss in the second process")
    time.sleep(0.5)  # the second is at the lock now (its miss is logged just before)
    open(os.path.join(folder, "go"), "w").close()
    outs = [p.communicate(timeout=120)[0] for p in (first, second)]
  finally:
    for p in procs:
      if p.poll() is None:
        p.kill()
  assert [p.returncode for p in (first, second)] == [0, 0], outs
  assert outs[0].splitlines()[-1] == outs[1].splitlines()[-1]  # the same program's result
  assert not os.path.exists(os.path.join(folder, "second-compiling"))  # XLA never compiled it there
  # (under load the second may also wait for a small program of JAX's own, e.g. jit_dynamic_slice,
  # that the first compiled in over 1 s: only the program of this test counts)
  waited = [line for line in open(log)
            if line.startswith(f"{second.pid}\t") and "Waited" in line and "jit__lambda" in line]
  assert len(waited) == 1 and "loaded from the cache" in waited[0], waited


def test_a_lock_that_cannot_be_had_leaves_the_compilation_to_go_on_unlocked(tmp_path, monkeypatch):
  """_acquire gives up (None) where the lock file cannot be made, and after WAIT_MAX_S where another
  holder never lets go (here another open file of this process), having waited that long."""
  import fcntl
  assert jax_private._acquire(str(tmp_path / "no-such-folder" / "x.lock"), "m") == (None, 0.0)
  path = str(tmp_path / "x.lock")
  with open(path, "a") as holder:
    fcntl.flock(holder, fcntl.LOCK_EX)
    monkeypatch.setattr(jax_private, "WAIT_MAX_S", 0.3)
    lock, waited = jax_private._acquire(path, "m")
    assert lock is None and waited >= 0.3
  lock, waited = jax_private._acquire(path, "m")  # free again
  assert lock is not None and waited < 0.3
  lock.close()

"""Test set-up: CPU JAX, the persistent compilation cache (outside the clone), shared compiled
simulators."""

import gc
import os
import pathlib  # noqa: F401  (a type in a hint)
import subprocess
import sys

os.environ.setdefault("JAX_PLATFORMS", "cpu")
# The suite's time is mostly XLA compiling programs that then run a few steps. LLVM without its
# optimization passes (-25 % compile time per program) and, where this jaxlib's XLA takes the flags
# (an unknown flag aborts the process, so a subprocess tries them first), the CPU's classic emitters
# instead of its fusion emitters, with instructions up to AVX: no FMA, which the classic emitters
# contract a*b+c into in some programs and not in others (1-ulp differences that fail the suite's
# bit-for-bit comparisons of two programs). tests/test_env.py's nav and des-hard steps, cold cache:
# 27 s with the first flag alone, 20 s with all three; the whole suite, cold, 2 cores: 12:09 -> 8:24.
# The persistent cache keys on XLA_FLAGS, so these programs never serve a run outside the tests.
# Set once (the pytest process); its workers and the subprocesses the tests start inherit them.
FAST_COMPILE = ("--xla_backend_optimization_level=0", "--xla_cpu_use_fusion_emitters=false", "--xla_cpu_max_isa=AVX")


def _xla_accepts(flags: str) -> bool:
  """Whether a JAX process starts its CPU backend with XLA_FLAGS = flags."""
  env = {**os.environ, "XLA_FLAGS": flags, "JAX_PLATFORMS": "cpu"}
  probe = subprocess.run([sys.executable, "-c", "import jax; jax.devices('cpu')"], env=env, capture_output=True,
                         timeout=300)
  return probe.returncode == 0


if "xla_backend_optimization_level" not in os.environ.get("XLA_FLAGS", ""):
  given = os.environ.get("XLA_FLAGS", "")
  wanted = f"{given} {' '.join(FAST_COMPILE)}".strip()
  os.environ["XLA_FLAGS"] = wanted if _xla_accepts(wanted) else f"{given} {FAST_COMPILE[0]}".strip()

import mjx_tracks  # noqa: E402,F401  (first: picks the headless GL backend before mujoco loads)
import jax  # noqa: E402
import pytest  # noqa: E402

from mjx_tracks import compile_cache  # noqa: E402

compile_cache.enable()

# Python's cyclic garbage collector: tracing a program makes millions of short-lived objects, and each
# full collection walks every object the process holds (a test worker holds more with each program it
# traces). The modules imported by now are moved out of its reach (they are never garbage), and the
# first generation collects after 10,000 new objects instead of 700, so fewer survive into the older
# ones. A cold suite, 2 cores (2026-11-29): each worker's full collections 10-12 instead of 36-47
# (~0.8 s each), its seconds in the collector 25-28 instead of 40-43 (of ~720-750 s of CPU).
gc.collect()
gc.freeze()
gc.set_threshold(10_000, 10, 10)


def pytest_configure(config):
  """A crashed xdist worker fails the session at once (--max-worker-restart 0 unless given): one
  restarted after a crash once left the session hung until CI's time limit."""
  if getattr(config.option, "maxworkerrestart", "absent") is None:
    config.option.maxworkerrestart = 0


@pytest.fixture(scope="session")
def default_physics():
  from mjx_tracks.envs.config import default_config
  return default_config().physics


@pytest.fixture(scope="session")
def jaguar_stairs(default_physics):
  """Robot 1 in the staircase world, compiled once for the whole session."""
  from mjx_tracks.robots import get_robot
  from mjx_tracks.sim.simulator import staircase_simulator
  return staircase_simulator(get_robot(1), default_physics)


@pytest.fixture(scope="session")
def absolem_stairs(default_physics):
  from mjx_tracks.robots import get_robot
  from mjx_tracks.sim.simulator import staircase_simulator
  return staircase_simulator(get_robot(2), default_physics)


def _session_folder(tmp_path_factory) -> "pathlib.Path":
  """A folder every pytest-xdist worker of this session shares (the session's own without xdist)."""
  base = tmp_path_factory.getbasetemp()
  return base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base


@pytest.fixture(scope="session")
def ppo_run(tmp_path_factory):
  """The session's one tiny PPO run (2,048 steps, a checkpoint after every 512-step update, a
  milestone at 1,024, the hardest probe at the end, compiled ahead beside the update (as on a GPU:
  train.core.ahead), one held-out staircase): made once by whichever
  worker asks first, under a file lock, and read by the test files of every worker. Tests copy it
  before changing it. Returns (run directory, database)."""
  import contextlib
  import fcntl
  import io
  from helpers import HELD_OUT_SET, TINY
  from train import run
  root = _session_folder(tmp_path_factory) / "ppo-run"
  out, database, said = root / "ppo", root / "db.sqlite", root / "ppo.stdout"
  root.mkdir(exist_ok=True)
  with open(root / "lock", "w") as lock:
    fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes
    if (root / "failed").exists():
      pytest.fail(f"the shared PPO run failed in another worker: {(root / 'failed').read_text()[-2000:]}")
    if not said.exists():
      with contextlib.redirect_stdout(io.StringIO()) as printed:
        rc = run.main(["--task", "asc-inc-cog", "--preset", "cpu", "--steps", "2048", "--out", str(out),
                       "--db", str(database), "--probe-every", "2048", "--milestones", "1024",
                       "--checkpoint-every", "0", "--keep-checkpoints", "4", "--compile-ahead", "on", *TINY,
                       "--set", HELD_OUT_SET])
      if rc != 0:
        (root / "failed").write_text(printed.getvalue())
        pytest.fail(f"the shared PPO run exited {rc}: {printed.getvalue()[-2000:]}")
      said.write_text(printed.getvalue())  # what the command printed, for the test of its last lines
  return str(out), str(database)


# Files that compile the most start first, longest first after the one that makes the shared PPO run
# (pytest-xdist hands files out in collection order): no long file starts last while the other worker
# idles. Each file's seconds in a cold suite on the 2-core machine (2026-11-29, --durations): training
# 89, env 96, group 73, evaluator 71, task_pack 68, runtime 44, physics_gate 42, sb3 39, export 36,
# stairs_physics 33, study_runner 30, compile_ahead 27, training_sac 24, brax_reference 23; the
# other ~65 files under 22 each, in name order after these.
FIRST = ("test_training.py", "test_env.py", "test_group.py", "test_evaluator.py", "test_task_pack.py",
         "test_runtime.py", "test_physics_gate.py", "test_sb3.py", "test_export.py", "test_stairs_physics.py",
         "test_study_runner.py", "test_compile_ahead.py", "test_training_sac.py", "test_brax_reference.py")


def pytest_collection_modifyitems(items):
  def rank(item):
    name = item.path.name
    return (FIRST.index(name), "") if name in FIRST else (len(FIRST), name)
  items.sort(key=rank)  # stable: each file's tests keep their order

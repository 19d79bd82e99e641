"""Test set-up: CPU JAX, a persistent (git-ignored) compilation cache, shared compiled simulators."""

import os
import pathlib

os.environ.setdefault("JAX_PLATFORMS", "cpu")

import mjx_tracks  # noqa: E402,F401  (first: picks the headless GL backend before mujoco loads)
import jax  # noqa: E402
import pytest  # noqa: E402

_CACHE = pathlib.Path(__file__).resolve().parent.parent / ".jax_cache"
jax.config.update("jax_compilation_cache_dir", str(_CACHE))
jax.config.update("jax_persistent_cache_min_compile_time_secs", 1.0)
jax.config.update("jax_persistent_cache_min_entry_size_bytes", 0)


@pytest.fixture(scope="session")
def jaguar_stairs():
  """Robot 1 in the staircase world, compiled once for the whole session."""
  from mjx_tracks.robots import get_robot
  from mjx_tracks.sim.simulator import staircase_simulator
  return staircase_simulator(get_robot(1))


@pytest.fixture(scope="session")
def absolem_stairs():
  from mjx_tracks.robots import get_robot
  from mjx_tracks.sim.simulator import staircase_simulator
  return staircase_simulator(get_robot(2))

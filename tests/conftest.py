"""Test set-up: CPU JAX, the persistent compilation cache (outside the clone), shared compiled
simulators."""

import os

os.environ.setdefault("JAX_PLATFORMS", "cpu")

import mjx_tracks  # noqa: E402,F401  (first: picks the headless GL backend before mujoco loads)
import jax  # noqa: E402
import pytest  # noqa: E402

from mjx_tracks import compile_cache  # noqa: E402

compile_cache.enable()


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

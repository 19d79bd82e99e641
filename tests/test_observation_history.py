"""observation.history: the policy sees the last k control steps' observations, newest first, with
copies of an episode's first observation before its first step (mjx_tracks.envs.observations.stack)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import TINY_SETTINGS

import mjx_tracks
from mjx_tracks.envs.config import ConfigError
from mjx_tracks.envs.observations import observation_names, stack
from mjx_tracks.envs.task_env import observation_names as env_names


def test_stack_puts_the_current_step_first_and_drops_the_oldest():
  a, b, c = (np.full(2, x, np.float32) for x in (1.0, 2.0, 3.0))
  first = stack(jnp.asarray(a), None, 3)
  np.testing.assert_array_equal(first, np.concatenate([a, a, a]))
  second = stack(jnp.asarray(b), first, 3)
  np.testing.assert_array_equal(second, np.concatenate([b, a, a]))
  np.testing.assert_array_equal(stack(jnp.asarray(c), second, 3), np.concatenate([c, b, a]))
  np.testing.assert_array_equal(stack(jnp.asarray(c), jnp.asarray(b), 1), c)


def test_older_steps_are_named_by_how_far_back_they_are():
  names = observation_names(("v", "flippers_paired"), {"v": 1, "flippers_paired": 2}, history=2)
  assert names == ["v", "flippers_paired[0]", "flippers_paired[1]",
                   "v@t-1", "flippers_paired[0]@t-1", "flippers_paired[1]@t-1"]


@pytest.mark.parametrize("history", [0, 17])
def test_a_history_out_of_range_is_refused_naming_the_key(history):
  with pytest.raises(ConfigError, match="observation.history"):
    mjx_tracks.load("asc-inc-cog", [f"observation.history={history}"])


def test_the_env_stacks_its_steps_and_restarts_the_stack_with_each_episode():
  """The tests' tiny task observes 2 steps (tests/helpers.py): after reset both halves are the
  first observation; after each step the older half is the previous step's newer half."""
  core = mjx_tracks.load("asc-inc-cog", TINY_SETTINGS)
  assert core.cfg.observation.history == 2
  n = sum(core.part_sizes.values())
  assert core.observation_size == 2 * n and len(env_names(core)) == 2 * n

  def rollout(key):
    s = core.reset(key)
    action = jnp.array([1.0, 0.6, -0.4, 0.5, -0.5])  # drive, flippers and arm move: the observation changes
    return s.obs, jax.lax.scan(lambda s, _: (core.step(s, action),) * 2, s, None, length=3)[1].obs

  first, obs = (np.asarray(x) for x in jax.jit(rollout)(jax.random.PRNGKey(0)))
  np.testing.assert_array_equal(first[:n], first[n:])
  previous = np.concatenate([first[None], obs[:-1]])
  np.testing.assert_array_equal(obs[:, n:], previous[:, :n])
  assert not np.allclose(obs[:, :n], previous[:, :n])  # the robot moved: the steps differ

"""Every registered task jits reset + 10 steps with finite observations; termination vs truncation;
the curriculum reset draws new scenes; Gymnasium's checker passes."""

import functools

import gymnasium as gym
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import mjx_tracks
from mjx_tracks.envs.config import available_tasks
from mjx_tracks.envs.task_env import METRICS
from mjx_tracks.envs.wrappers import batched_env

N_ENVS = 2


@functools.lru_cache(maxsize=None)
def _compiled(task: str):
  core = mjx_tracks.load(task)
  env = batched_env(core)
  return core, env, jax.jit(env.reset), jax.jit(env.step)


@pytest.mark.parametrize("task", available_tasks())
def test_task_jits_reset_and_ten_steps_with_finite_observations(task):
  core, _, reset, step = _compiled(task)
  s = reset(jax.random.split(jax.random.PRNGKey(0), N_ENVS))
  assert s.obs.shape == (N_ENVS, core.observation_size)
  key = jax.random.PRNGKey(1)
  for _ in range(10):
    key, k = jax.random.split(key)
    s = step(s, jax.random.uniform(k, (N_ENVS, core.action_size), minval=-1, maxval=1))
    assert np.isfinite(np.asarray(s.obs)).all() and np.isfinite(np.asarray(s.reward)).all()
  assert s.obs.shape == (N_ENVS, core.observation_size)
  assert set(s.metrics) == set(METRICS)
  assert float(np.asarray(s.metrics["physics_nan"]).sum()) == 0.0


def _upside_down(state):
  es = state.pipeline_state
  q = es.data.qpos.at[:, 3:7].set(jnp.array([0.0, 1.0, 0.0, 0.0]))  # rolled by pi
  q = q.at[:, 2].set(0.4)
  return state.replace(pipeline_state=es.replace(data=es.data.replace(qpos=q)))


def test_tip_over_terminates_with_penalty():
  core, _, reset, step = _compiled("asc-inc-cog")
  s = _upside_down(reset(jax.random.split(jax.random.PRNGKey(0), N_ENVS)))
  s = step(s, jnp.zeros((N_ENVS, core.action_size)))
  assert np.asarray(s.done).all()
  assert not np.asarray(s.info["truncation"]).any()
  assert np.asarray(s.metrics["tipped_over"]).all()
  assert (np.asarray(s.metrics["reward/tipover"]) == -1.0).all()


def test_time_limit_truncates_and_does_not_terminate():
  core, _, reset, step = _compiled("asc-inc-cog")
  s = reset(jax.random.split(jax.random.PRNGKey(0), N_ENVS))
  s.info["steps"] = jnp.full(N_ENVS, core.cfg.episode.max_steps - 1.0)
  s = step(s, jnp.zeros((N_ENVS, core.action_size)))
  assert np.asarray(s.done).all()
  assert np.asarray(s.info["truncation"]).all()  # ended by the limit, not by the task
  assert not np.asarray(s.metrics["tipped_over"]).any()


def test_finished_episodes_restart_on_a_new_scene():
  core, _, reset, step = _compiled("asc-uni-cog")
  s = reset(jax.random.split(jax.random.PRNGKey(0), N_ENVS))
  before = np.asarray(s.pipeline_state.scene.xi)
  s = _upside_down(s)
  s = step(s, jnp.zeros((N_ENVS, core.action_size)))
  after = np.asarray(s.pipeline_state.scene.xi)
  assert not np.allclose(before, after)
  assert np.asarray(s.info["global"].curriculum.finished)[0] == N_ENVS
  np.testing.assert_allclose(np.asarray(s.pipeline_state.data.qpos[:, 2]), core.robot.spawn_height + 0.005,
                             atol=1e-5)  # back at the spawn, upright


def test_gymnasium_checker_passes_and_vector_env_steps():
  env = gym.make("mjx_tracks/asc-inc-cog-v0", render_mode="rgb_array")
  check_env(env.unwrapped, skip_render_check=False)
  env.reset(seed=3)
  frame = env.render()
  assert frame.ndim == 3 and frame.shape[2] == 3 and frame.std() > 0
  venv = gym.make_vec("mjx_tracks/asc-inc-cog-v0", num_envs=3)
  obs, _ = venv.reset(seed=0)
  assert obs.shape == (3, venv.single_observation_space.shape[0])
  obs, rew, term, trunc, info = venv.step(venv.action_space.sample())
  assert obs.dtype == np.float32 and rew.shape == (3,) and "final_obs" in info


def test_bad_task_settings_fail_clearly():
  from mjx_tracks.envs.config import ConfigError
  with pytest.raises(ConfigError, match="arm"):
    mjx_tracks.load("asc-inc-cog", ["robot=2"])

"""Every registered task builds and traces reset + step, one task of each direction and scene kind
runs 10 steps with finite observations; termination vs truncation; the curriculum reset draws new
scenes; Gymnasium's checker passes."""

import functools

import gymnasium as gym
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import mjx_tracks
from mjx_tracks.envs.config import available_tasks, load_config
from mjx_tracks.envs.task_env import METRICS
from mjx_tracks.envs.wrappers import batched_env

N_ENVS = 2  # robots of a compiled task, but:
# asc-inc-cog's is the Gymnasium Env's batch, so that its test loads these programs from the
# persistent cache; the mixed terrain task's reset draws every kind (checked) from that many
TASK_ENVS = {"asc-inc-cog": 1, "mixed-terrain": 16}
TERRAIN_SEED = 4
# compiled and stepped: one per direction, scene kind, robot and terrain world (the corridor's, the
# spirals' in the open); between them they run every sampler, reward kind, direction and terrain
# kind (the mixed task draws each corridor kind; spiral-down differs from spiral-up in its kind
# only), so every other task,
# differing from one of them in those keys only (checked below), runs code they compile; a task
# differing in a size as well (a box pool) is traced to check its shapes
# (des-hard: the descent, with the episode_mean safety form and a goal bonus; the paper's descent differs in data only)
RUN_TASKS = ("asc-inc-cog", "des-hard", "nav", "mixed-terrain", "asc-inc-cog-r2", "spiral-up")
EXERCISED_KEYS = {"task", "scene.sampler", "reward.kind", "scene.direction", "scene.terrains", "episode.max_steps",
                  "reward.safety_form", "reward.angular_scale", "reward.goal_bonus", "scene.tread", "scene.riser",
                  "observation.noise", "evaluation.held_out_terrain", "evaluation.held_out_nav",
                  "scene.nav_gap", "reward.collision_penalty"}  # hidden rays: tests/test_randomization.py compiles every randomization path;
#                     held-out terrains and areas are evaluation scenes; a gap range and the collision penalty are
#                     constants of nav's code
DATA_PREFIXES = ("scene.terrain.",)  # a terrain kind's ranges: the sampler's data (its box pool is scenes.terrain.POOL)
# traced here: shapes or state change, or a code path of its own (a floor layout's way round:
# tests/test_nav_floor_passage.py compiles it)
SIZE_KEYS = {"scene.steps", "scene.nav_floor_obstacles", "randomization.enabled", "scene.nav_floor_passage"}
OBS_SIZE_KEYS = {"observation.scan_pitches"}  # more scan rings: nav's scan code, a longer observation (traced)


@functools.lru_cache(maxsize=None)
def _compiled(task: str):
  """(core, batched env, reset(keys), step, robots): the programs the Gymnasium stack compiles."""
  core = mjx_tracks.load(task)
  env = batched_env(core)
  reset_with = jax.jit(env.reset_with)
  return core, env, lambda keys: reset_with(keys, env.initial_stats()), jax.jit(env.step), TASK_ENVS.get(task, N_ENVS)


def _flat(d: dict, prefix: str = "") -> dict:
  out = {}
  for k, v in d.items():
    out.update(_flat(v, f"{prefix}{k}.") if isinstance(v, dict) else {prefix + k: v})
  return out


@pytest.mark.parametrize("task", sorted(set(available_tasks()) - set(RUN_TASKS)))
def test_every_other_task_differs_from_a_run_task_only_in_keys_the_run_tasks_exercise(task):
  """Its sizes match that run task's; a task with a size of its own is traced (no XLA compilation)."""
  core = mjx_tracks.load(task)
  cfg = _flat(core.cfg.to_dict())
  runs = {t: _flat(load_config(t).to_dict()) for t in RUN_TASKS}
  diffs = {t: {k for k in cfg if cfg[k] != run.get(k)} for t, run in runs.items()}
  diffs = {t: {k for k in d if not k.startswith(DATA_PREFIXES)} for t, d in diffs.items()}
  near = [t for t, d in diffs.items() if d <= EXERCISED_KEYS | SIZE_KEYS | OBS_SIZE_KEYS]
  assert near, diffs
  run = mjx_tracks.load(near[0])
  assert core.action_size == run.action_size
  assert core.observation_size == run.observation_size or diffs[near[0]] & OBS_SIZE_KEYS
  if diffs[near[0]] & (SIZE_KEYS | OBS_SIZE_KEYS):  # one robot's reset and step (the batch's wrapper is shape-blind)
    s = jax.eval_shape(core.reset, jax.random.PRNGKey(0))
    s = jax.eval_shape(core.step, s, jax.ShapeDtypeStruct((core.action_size,), jnp.float32))
    assert s.obs.shape == (core.observation_size,) and set(s.metrics) == set(METRICS)


@pytest.mark.parametrize("task", RUN_TASKS)
def test_task_jits_reset_and_ten_steps_with_finite_observations(task):
  core, _, reset, step, n = _compiled(task)
  terrain = core.cfg.scene.kind == "terrain"
  s = reset(jax.random.split(jax.random.PRNGKey(TERRAIN_SEED if terrain else 0), n))
  assert s.obs.shape == (n, core.observation_size)
  if terrain:
    assert set(np.asarray(s.pipeline_state.scene.variant)) == set(range(len(core.cfg.scene.terrains)))
  key = jax.random.PRNGKey(1)
  for _ in range(10):
    key, k = jax.random.split(key)
    s = step(s, jax.random.uniform(k, (n, core.action_size), minval=-1, maxval=1))
    assert np.isfinite(np.asarray(s.obs)).all() and np.isfinite(np.asarray(s.reward)).all()
  assert s.obs.shape == (n, core.observation_size)
  assert set(s.metrics) == set(METRICS)
  assert float(np.asarray(s.metrics["physics_nan"]).sum()) == 0.0


def _upside_down(state):
  es = state.pipeline_state
  q = es.data.qpos.at[:, 3:7].set(jnp.array([0.0, 1.0, 0.0, 0.0]))  # rolled by pi
  q = q.at[:, 2].set(0.4)
  return state.replace(pipeline_state=es.replace(data=es.data.replace(qpos=q)))


def test_tip_over_terminates_with_penalty():
  core, _, reset, step, n = _compiled("asc-inc-cog")
  s = _upside_down(reset(jax.random.split(jax.random.PRNGKey(0), n)))
  s = step(s, jnp.zeros((n, core.action_size)))
  assert np.asarray(s.done).all()
  assert not np.asarray(s.info["truncation"]).any()
  assert np.asarray(s.metrics["tipped_over"]).all()
  assert (np.asarray(s.metrics["reward/tipover"]) == -1.0).all()


def test_time_limit_truncates_and_does_not_terminate():
  core, _, reset, step, n = _compiled("asc-inc-cog")
  s = reset(jax.random.split(jax.random.PRNGKey(0), n))
  s.info["steps"] = jnp.full_like(s.info["steps"], core.cfg.episode.max_steps - 1.0)  # not weakly typed: no new trace
  s = step(s, jnp.zeros((n, core.action_size)))
  assert np.asarray(s.done).all()
  assert np.asarray(s.info["truncation"]).all()  # ended by the limit, not by the task
  assert not np.asarray(s.metrics["tipped_over"]).any()


def test_finished_episodes_restart_on_a_new_scene():
  core, _, reset, step, n = _compiled("nav")  # a run task (compiled once) whose uniform sampler redraws at any eps
  s = reset(jax.random.split(jax.random.PRNGKey(0), n))
  before = np.asarray(s.pipeline_state.scene.xi)
  s = _upside_down(s)
  s = step(s, jnp.zeros((n, core.action_size)))
  after = np.asarray(s.pipeline_state.scene.xi)
  assert not np.allclose(before, after)
  assert np.asarray(s.info["global"].curriculum.finished)[0] == n
  scene = s.pipeline_state.scene
  spawn, yaw = np.asarray(scene.spawn_pos), np.asarray(scene.spawn_yaw)
  np.testing.assert_allclose(np.asarray(s.pipeline_state.data.qpos[:, :2]), spawn[:, :2], atol=1e-6)
  upright = np.stack([np.cos(yaw / 2), 0 * yaw, 0 * yaw, np.sin(yaw / 2)], axis=-1)
  np.testing.assert_allclose(np.asarray(s.pipeline_state.data.qpos[:, 3:7]), upright, atol=1e-6)  # back at the spawn, upright


def test_unfinished_environments_are_untouched_by_the_auto_reset():
  """Env 0 tips over and is reset; env 1 ends in exactly the state it reaches when env 0 does not."""
  core, env, reset, step, n = _compiled("nav")
  s = reset(jax.random.split(jax.random.PRNGKey(2), n))
  keep = lambda a, b: jnp.concatenate([a[:1], b[1:]])  # env 0 tipped, env 1 as it was
  mixed = s.replace(pipeline_state=jax.tree_util.tree_map(keep, _upside_down(s).pipeline_state, s.pipeline_state))
  action = jnp.full((n, core.action_size), 0.3, jnp.float32)  # not weakly typed: no new trace
  after, reference = step(mixed, action), step(s, action)
  assert np.asarray(after.done).tolist() == [1.0, 0.0] and not np.asarray(reference.done).any()
  for a, b in zip(jax.tree_util.tree_leaves(after.pipeline_state), jax.tree_util.tree_leaves(reference.pipeline_state)):
    np.testing.assert_array_equal(np.asarray(a)[1], np.asarray(b)[1])
  np.testing.assert_array_equal(np.asarray(after.obs)[1], np.asarray(reference.obs)[1])
  scene = after.pipeline_state.scene
  spawn, yaw = np.asarray(scene.spawn_pos)[0], float(np.asarray(scene.spawn_yaw)[0])
  np.testing.assert_allclose(np.asarray(after.pipeline_state.data.qpos)[0, :2], spawn[:2], atol=1e-6)
  upright = [np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2)]  # at the new scene's spawn, upright
  np.testing.assert_allclose(np.asarray(after.pipeline_state.data.qpos)[0, 3:7], upright, atol=1e-6)


def test_a_physics_blow_up_ends_the_episode_and_is_counted():
  """Velocities of 1e30 m/s make the integration overflow: the step keeps the last finite state,
  ends the episode and counts it in physics_nan, with finite observations and rewards."""
  core, _, reset, step, n = _compiled("asc-inc-cog")
  s = reset(jax.random.split(jax.random.PRNGKey(3), n))
  es = s.pipeline_state
  s = s.replace(pipeline_state=es.replace(data=es.data.replace(qvel=jnp.full_like(es.data.qvel, 1e30))))
  s = step(s, jnp.zeros((n, core.action_size)))
  assert np.asarray(s.metrics["physics_nan"]).tolist() == [1.0] * n
  assert np.asarray(s.done).all() and not np.asarray(s.info["truncation"]).any()
  assert np.isfinite(np.asarray(s.info["final_obs"])).all() and np.isfinite(np.asarray(s.reward)).all()
  assert int(np.asarray(s.info["global"].curriculum.finished)[0]) == n


def test_navigation_ends_at_the_goal_and_when_moving_away():
  """Env 0 is put on its goal; env 1's start distance is shrunk to 0.5 m, so where it stands it is
  more than 1.2 start distances from the goal."""
  core, _, reset, step, n = _compiled("nav")
  s = reset(jax.random.split(jax.random.PRNGKey(4), n))
  es = s.pipeline_state
  goal = np.asarray(es.scene.goal)
  q = es.data.qpos.at[0, :2].set(goal[0, :2])
  es = es.replace(data=es.data.replace(qpos=q), d0=es.d0.at[1].set(0.5), closest=es.closest.at[1].set(0.5))
  s = step(s.replace(pipeline_state=es), jnp.zeros((n, core.action_size)))
  assert np.asarray(s.done).tolist() == [1.0, 1.0]
  assert np.asarray(s.metrics["goal_reached"]).tolist() == [1.0, 0.0]
  assert np.asarray(s.metrics["moved_away"]).tolist() == [0.0, 1.0]
  assert not np.asarray(s.metrics["tipped_over"]).any()


def test_navigation_measures_the_free_space_path_and_a_collision_ends_the_episode():
  """The start distance is the scene's free-space distance minus the tolerance; env 0 is put with
  its left side 0.1 m inside the first wall obstacle's near face: the step counts a collision,
  charges the penalty and ends the episode; env 1, in the open, does not."""
  core, _, reset, step, n = _compiled("nav")
  cfg = core.cfg
  assert cfg.episode.distance == "geodesic" and cfg.episode.end_on_collision and cfg.reward.collision_penalty > 0
  s = reset(jax.random.split(jax.random.PRNGKey(8), n))
  es = s.pipeline_state
  chassis = es.data.xpos[:, core.sim.layout.chassis_body]
  free = jax.jit(jax.vmap(core.scene.free_space_distance))(es.scene, chassis)
  np.testing.assert_allclose(np.asarray(es.d0), np.asarray(free) - cfg.episode.goal_tolerance, rtol=1e-5)
  box_pos, box_size = np.asarray(es.scene.box_pos[0, 0]), np.asarray(es.scene.box_size[0, 0])
  face_y = box_pos[1] - box_size[1]  # the obstacle juts from the left wall: its face toward -y
  q = es.data.qpos.at[0, :3].set(jnp.array([box_pos[0], face_y - 0.405 + 0.1, es.data.qpos[0, 2]]))
  q = q.at[0, 3:7].set(jnp.array([1.0, 0.0, 0.0, 0.0]))  # heading +x, the left flippers toward the face
  s = step(s.replace(pipeline_state=es.replace(data=es.data.replace(qpos=q))), jnp.zeros((n, core.action_size)))
  assert np.asarray(s.metrics["collision"]).tolist() == [1.0, 0.0]
  assert np.asarray(s.done).tolist() == [1.0, 0.0]
  np.testing.assert_allclose(np.asarray(s.metrics["reward/collision"]), [-cfg.reward.collision_penalty, 0.0])


def test_the_spawn_is_off_the_stairs_and_the_cog_term_waits_for_them():
  core, _, reset, step, n = _compiled("asc-inc-cog")
  s = step(reset(jax.random.split(jax.random.PRNGKey(5), n)), jnp.zeros((n, core.action_size)))
  assert np.asarray(s.metrics["on_stairs"]).tolist() == [0.0] * n  # spawned 1 m before the first riser
  assert np.asarray(s.metrics["cog_deviation"]).tolist() == [0.0] * n


def test_observation_parts_read_their_sources():
  """Each part of the paper's stair observation against where it comes from."""
  from mjx_tracks.envs.beams import depth_beams
  from mjx_tracks.sim.pose import chassis_rpy
  core, _, reset, step, n = _compiled("asc-inc-cog")
  s = reset(jax.random.split(jax.random.PRNGKey(6), n))
  s = step(s, jnp.tile(jnp.array([1.0, 0.6, -0.4, 0.5, -0.5]), (n, 1)))
  obs, es = np.asarray(s.obs[0]), jax.tree_util.tree_map(lambda x: x[0], s.pipeline_state)
  sizes = core.part_sizes
  offsets = np.cumsum([0] + [sizes[p] for p in core.cfg.observation.parts])
  part = {p: obs[offsets[i]:offsets[i + 1]] for i, p in enumerate(core.cfg.observation.parts)}
  q = np.asarray(es.data.qpos)
  joints = q[core.sim.layout.joint_qpos]
  names = core.robot.joint_names()
  front = [names.index("flipper_front_left"), names.index("flipper_front_right")]
  rear = [names.index("flipper_rear_left"), names.index("flipper_rear_right")]
  np.testing.assert_allclose(part["flippers_paired"], [joints[front].mean(), joints[rear].mean()], atol=1e-6)
  np.testing.assert_allclose(part["arm"], joints[[names.index("arm_1"), names.index("arm_2")]], atol=1e-6)
  np.testing.assert_allclose(part["pitch"], np.asarray(chassis_rpy(jnp.asarray(q)))[1], atol=1e-6)
  rot = np.asarray(es.data.xmat[core.sim.layout.chassis_body])
  np.testing.assert_allclose(part["v"], (rot.T @ np.asarray(es.data.qvel[:3]))[0], atol=1e-5)
  assert part["v"][0] > 0.1  # driving forward
  m = core.sim.with_boxes(es.scene.box_pos, es.scene.box_size)
  beams = np.asarray(jax.jit(lambda m, d: depth_beams(core.beams, m, d, core.sim.layout.camera_site))(m, es.data))
  np.testing.assert_allclose(part["vertical_beams"], beams[: core.cfg.observation.vertical_beams], atol=1e-5)
  assert (part["vertical_beams"] > 0).any()  # the camera sees the floor and the first step


def test_gymnasium_checker_passes_and_vector_env_steps(capsys):
  env = gym.make("mjx_tracks/asc-inc-cog-v0", render_mode="rgb_array")  # this file's first Gymnasium env
  said = capsys.readouterr().err
  assert "compiling asc-inc-cog for 1 robot(s)" in said and "compiled in" in said  # not a silent minute
  check_env(env.unwrapped, skip_render_check=False)
  env.reset(seed=3)
  frame = env.render()
  assert frame.ndim == 3 and frame.shape[2] == 3 and frame.std() > 0
  venv = gym.make_vec("mjx_tracks/asc-inc-cog-v0", num_envs=1)  # one robot: the Env's compiled stack, shared
  obs, info = venv.reset(seed=0)
  assert obs.shape == (1, venv.single_observation_space.shape[0]) and info["eps"].shape == (1,)
  obs, rew, term, trunc, info = venv.step(venv.action_space.sample())
  assert obs.dtype == np.float32 and rew.shape == (1,) and "final_obs" in info and "eps" in info


def test_gymnasium_env_keeps_its_curriculum_across_resets():
  """A forward-driving policy for 20 episodes (the curriculum's window) of one Env: the eps reported
  at reset rises above 0 and, with the window's missing episodes counted as 0, stays below 1 early on."""
  env = gym.make("mjx_tracks/asc-inc-cog-v0").unwrapped
  forward = np.array([1.0, 0.3, 0.0, 0.0, 0.0], np.float32)
  eps_at_reset = []
  _, info = env.reset(seed=0)
  for _ in range(20):
    eps_at_reset.append(info["eps"])
    done = False
    while not done:
      _, _, term, trunc, step_info = env.step(forward)
      assert "eps" in step_info
      done = term or trunc
    _, info = env.reset()
  window = env._stack.core.cfg.scene.curriculum.window
  assert eps_at_reset[0] == 0.0 and max(eps_at_reset) > 0.0
  assert all(e <= (i / window) + 1e-6 for i, e in enumerate(eps_at_reset[:window]))  # < 1 early on
  kept = env.curriculum_state()
  assert int(kept.curriculum.finished) == 20
  fresh = gym.make("mjx_tracks/asc-inc-cog-v0").unwrapped
  fresh.set_curriculum_state(kept)
  assert fresh.reset(seed=1)[1]["eps"] == pytest.approx(float(kept.curriculum.eps))


def test_bad_task_settings_fail_clearly():
  from mjx_tracks.envs.config import ConfigError
  with pytest.raises(ConfigError, match="arm"):
    mjx_tracks.load("asc-inc-cog", ["robot=2"])


def test_the_step_hands_the_curriculum_eps_of_its_state_to_the_dof_curriculum():
  """Traced (no compilation): the controller decodes each action at the eps in the state's info."""
  core = mjx_tracks.load("asc-inc-cog", ["control.dof_curriculum=[[front, 0.3], [arm_1, 0.6]]"])
  real, seen = core.controller, []
  assert real.unlock.tolist() == pytest.approx([0.0, 0.3, 0.0, 0.6, 0.0])  # v, front, rear, arm_1, arm_2

  class Spy:
    def __getattr__(self, name):
      return getattr(real, name)

    def decode(self, action, prev, eps=None):
      seen.append(eps)
      return real.decode(action, prev, eps)

  core.controller = Spy()

  def step(state, eps):
    core.step(state.replace(info={**state.info, "eps": eps}), jnp.zeros(core.action_size))
    assert len(seen) == 1 and seen[0] is eps
    return eps

  s = jax.eval_shape(core.reset_at, jax.random.PRNGKey(0), jnp.float32(0.4), jnp.float32(1.0))
  jax.eval_shape(step, s, jax.ShapeDtypeStruct((), jnp.float32))

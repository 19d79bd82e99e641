"""Evaluation scenes as data: every evaluation scene of a stair task is drawn by one program from its
draw (train.evaluation.scene_programs), exactly as the scene's own generator draws it; the other
kinds keep a program per scene where their scenes differ in more than a draw."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from mjx_tracks.envs.config import load_config
from scenes import samplers
from scenes.kinds import scene_kind
from scenes.staircase import stair_ranges
from train.evaluation import scene_config, scene_programs, suite_scenes

KEYS = jax.random.split(jax.random.PRNGKey(3), 256)


def _sample(scene_gen, eps, draw=None):
  return jax.jit(jax.vmap(lambda k: scene_gen.sample(k, eps, draw) if draw is not None else scene_gen.sample(k, eps)))(KEYS)


@pytest.mark.parametrize("task", ["asc-inc-cog", "des-inc-ang"])
def test_every_stair_scene_is_drawn_by_one_program_as_its_own_generator_draws_it(task):
  cfg = load_config(task)
  scenes = [*suite_scenes(cfg), "incremental", "train"]
  programs = scene_programs(cfg, scenes)
  assert len(programs) == 1, "one program for every evaluation scene of a stair task"
  program, draws = programs[0]
  assert list(draws) == scenes
  kind = scene_kind(cfg.scene.kind)
  shared = kind.make(program.scene)
  most_steps = max(scene_config(cfg, s).scene.steps[1] for s in scenes)
  assert shared.n_boxes == most_steps  # the pool holds the longest staircase of any scene
  eps = jnp.float32(0.6)  # the incremental scenes' difficulty: their draws depend on it
  for scene in scenes:
    own = kind.make(scene_config(cfg, scene).scene)
    want, got = _sample(own, eps), _sample(shared, eps, draws[scene])
    n = own.n_boxes  # the boxes past its own pool are parked in the shared one
    np.testing.assert_array_equal(got.xi, want.xi, err_msg=scene)
    for field in ("spawn_pos", "spawn_yaw", "goal", "goal_halfwidth"):
      np.testing.assert_array_equal(getattr(got, field), getattr(want, field), err_msg=f"{scene} {field}")
    np.testing.assert_array_equal(got.box_pos[:, :n], want.box_pos, err_msg=scene)
    np.testing.assert_array_equal(got.box_size[:, :n], want.box_size, err_msg=scene)
    assert np.all(got.box_pos[:, n:, 2] < -5.0), f"{scene}: the shared pool's extra boxes are parked below the floor"
  hardest = np.asarray(_sample(shared, eps, draws["hardest"]).xi)
  assert np.all(hardest == hardest[0]) and hardest[0, 2] == cfg.scene.steps[1]  # a range of width 0: pinned


def test_a_draw_as_data_follows_the_sampler_it_names():
  r = stair_ranges((0.3, 0.5), (0.1, 0.2), (2, 6))
  key, eps = jax.random.PRNGKey(0), jnp.float32(0.4)
  for sampler in samplers.SAMPLERS:
    want = samplers.sample(key, eps, r, sampler, "difficulty")
    got = samplers.sample(key, eps, r, "uniform", "difficulty", samplers.as_draw(r, sampler))
    np.testing.assert_array_equal(got, want, err_msg=sampler)
  with pytest.raises(ValueError, match="unknown sampler"):
    samplers.as_draw(r, "gaussian")


def test_terrain_scenes_of_one_kind_alone_keep_their_own_programs():
  cfg = load_config("mixed-terrain")
  scenes = suite_scenes(cfg)
  programs = scene_programs(cfg, scenes)
  assert sum(len(d) for _, d in programs) == len(scenes)
  assert len(programs) == len(scenes)  # terrain kinds take no draw yet: a program per scene, as before
  assert all(draw is None for _, d in programs for draw in d.values())

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


def _sample(scene_gen, eps):
  """The generator's own draws for KEYS."""
  return jax.jit(jax.vmap(lambda k: scene_gen.sample(k, eps)))(KEYS)


def _sampler_of_draws(scene_gen, eps):
  """draw -> the generator's draws for KEYS from that draw: one compiled program for every draw."""
  compiled = jax.jit(jax.vmap(lambda k, d: scene_gen.sample(k, eps, d), in_axes=(0, None)))
  return lambda draw: compiled(KEYS, draw)


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
  shared_sample = _sampler_of_draws(shared, eps)
  for scene in scenes:
    own = kind.make(scene_config(cfg, scene).scene)
    want, got = _sample(own, eps), shared_sample(draws[scene])
    n = own.n_boxes  # the boxes past its own pool are parked in the shared one
    np.testing.assert_array_equal(got.xi, want.xi, err_msg=scene)
    for field in ("spawn_pos", "spawn_yaw", "goal", "goal_halfwidth"):
      np.testing.assert_array_equal(getattr(got, field), getattr(want, field), err_msg=f"{scene} {field}")
    np.testing.assert_array_equal(got.box_pos[:, :n], want.box_pos, err_msg=scene)
    np.testing.assert_array_equal(got.box_size[:, :n], want.box_size, err_msg=scene)
    assert np.all(got.box_pos[:, n:, 2] < -5.0), f"{scene}: the shared pool's extra boxes are parked below the floor"
  hardest = np.asarray(shared_sample(draws["hardest"]).xi)
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


@pytest.mark.parametrize("task", ["mixed-terrain", "nav"])
def test_terrain_and_navigation_scenes_share_a_program_where_only_their_draw_differs(task):
  """A terrain task's scenes (hardest, uniform, each kind alone, held-out terrains) draw in one
  program; a navigation task's uniform and single-area scenes in one, its held-out areas (another
  gap or obstacle count) apart. Each shared scene draws what its own generator draws."""
  cfg = load_config(task)
  scenes = suite_scenes(cfg)
  programs = scene_programs(cfg, scenes)
  terrain = cfg.scene.kind == "terrain"
  assert len(programs) == (1 if terrain else 1 + len(cfg.evaluation.held_out_nav))
  program, draws = programs[0]
  kind = scene_kind(cfg.scene.kind)
  shared = kind.make(program.scene)
  eps = jnp.float32(0.6)
  shared_sample = _sampler_of_draws(shared, eps)
  names = program.scene.terrains if terrain else program.scene.nav_kinds
  checked = [s for s in draws if s in ("hardest", "uniform")] + [  # the first of each other sort
      next(s for s in draws if s.startswith(p)) for p in ("hardest/", "held-out/", "nav/") if any(s.startswith(p) for s in draws)]
  for scene in checked:
    draw = draws[scene]
    own_cfg = scene_config(cfg, scene)
    own = kind.make(own_cfg.scene)
    want, got = _sample(own, eps), shared_sample(draw)
    for field in ("box_pos", "box_size", "box_yaw", "spawn_pos", "spawn_yaw", "goal", "goal_halfwidth"):
      np.testing.assert_array_equal(getattr(got, field), getattr(want, field), err_msg=f"{scene} {field}")
    if terrain:  # the kind by name
      own_kinds = own_cfg.scene.terrains
      assert [names[i] for i in np.asarray(got.variant)] == [own_kinds[i] for i in np.asarray(want.variant)], scene
      for i, k in enumerate(own_kinds):  # each kind's parameters where the program's xi holds them
        j = list(names).index(k)
        (a, b), (c, d) = shared.offsets()[j:j + 2], own.offsets()[i:i + 2]
        rows = np.asarray(want.variant) == i
        np.testing.assert_array_equal(got.xi[rows, a:b], want.xi[rows, c:d], err_msg=f"{scene} {k}")
    else:
      np.testing.assert_array_equal(got.xi, want.xi, err_msg=scene)
      np.testing.assert_array_equal(got.variant, want.variant, err_msg=scene)
  if len(names) > 1:  # both samplers and the kinds mask were exercised: the draws differ by scene
    assert len({tuple(np.asarray(d.kinds)) for d in draws.values()}) > 1



def test_a_kinds_mask_draws_uniformly_among_the_kinds_it_allows():
  """pick_kind: with kinds [T, F, T, T] each allowed kind has probability 1/3 (20,000 draws: within
  5 standard deviations of the binomial), the other never; with every kind allowed, the index
  drawn without a mask."""
  keys = jax.random.split(jax.random.PRNGKey(7), 20_000)
  r = stair_ranges((0.3, 0.5), (0.1, 0.2), (2, 6))
  mask = samplers.as_draw(r, "uniform", [True, False, True, True])
  picks = np.asarray(jax.vmap(lambda k: samplers.pick_kind(k, 4, mask))(keys))
  counts = np.bincount(picks, minlength=4)
  n, p = len(keys), 1 / 3
  assert counts[1] == 0
  assert np.all(np.abs(counts[[0, 2, 3]] - n * p) < 5 * np.sqrt(n * p * (1 - p))), counts
  every = samplers.as_draw(r, "uniform", [True] * 4)
  np.testing.assert_array_equal(jax.vmap(lambda k: samplers.pick_kind(k, 4, every))(keys[:500]),
                                jax.vmap(lambda k: samplers.pick_kind(k, 4))(keys[:500]))

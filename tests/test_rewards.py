"""Reward terms against hand-computed cases."""

import jax.numpy as jnp
import numpy as np
import pytest

import dataclasses

from mjx_tracks.envs.config import default_config
from mjx_tracks.envs.rewards import (ON_STAIRS_MARGIN, Monitor, cog_deviation, goal_distance, goal_reached,
                                     normalizer_init, normalizer_update, on_stairs, progress_step)

_D = default_config()
EP = _D.episode
NO_HIT = jnp.bool_(False)  # the step touched no wall or obstacle


def RewardConfig(**kw):
  return dataclasses.replace(_D.reward, **kw)


def test_moving_half_a_metre_toward_a_goal_two_metres_away_earns_a_quarter():
  goal = jnp.array([2.3, 0.0, 0.0])
  d0 = goal_distance(jnp.zeros(3), goal, 0.0, 0.3)
  assert float(d0) == pytest.approx(2.0)
  dist = goal_distance(jnp.array([0.5, 0, 0]), goal, 0.0, 0.3)
  r, closest = progress_step(dist, d0, d0)
  assert float(r) == pytest.approx(0.25) and float(closest) == pytest.approx(1.5)
  # moving back and forth earns nothing until the closest distance is beaten again
  back = goal_distance(jnp.array([0.2, 0, 0]), goal, 0.0, 0.3)
  r2, closest2 = progress_step(back, closest, d0)
  assert float(r2) == 0.0 and float(closest2) == pytest.approx(1.5)
  r3, closest3 = progress_step(goal_distance(jnp.array([1.0, 0, 0]), goal, 0.0, 0.3), closest2, d0)
  assert float(r3) == pytest.approx(0.25)
  # overshooting the goal completes the episode's progress at exactly 1 in total
  r4, _ = progress_step(goal_distance(jnp.array([2.2, 0, 0]), goal, 0.0, 0.3), closest3, d0)
  assert float(r + r3 + r4) == pytest.approx(1.0)


def test_potential_progress_pays_back_a_detour_and_sums_to_the_distance_covered():
  """Goal 2 m away: 0.5 m toward it (+0.25), 1 m back (-0.5), 1.5 m toward it (+0.75), then to it."""
  d0 = jnp.float32(2.0)
  total, prev = 0.0, d0
  for dist, want in ((1.5, 0.25), (2.5, -0.5), (1.0, 0.75), (-0.1, 0.5)):  # below 0: reached, counts as 0
    r, prev = progress_step(jnp.float32(dist), prev, d0, "potential")
    assert float(r) == pytest.approx(want)
    total += float(r)
  assert total == pytest.approx(1.0)
  # the paper's rule pays the same first 0.5 m, nothing for the way back, then only the new ground
  r, closest = progress_step(jnp.float32(1.5), d0, d0, "closest")
  r2, closest = progress_step(jnp.float32(2.5), closest, d0, "closest")
  r3, _ = progress_step(jnp.float32(1.0), closest, d0, "closest")
  assert [float(r), float(r2), float(r3)] == pytest.approx([0.25, 0.0, 0.25])


def test_a_collision_costs_its_penalty_and_ends_the_episode_only_if_asked():
  upright, args = jnp.zeros(3), (jnp.float32(1.5), jnp.float32(2.0), jnp.float32(2.0))
  for end in (False, True):
    mon = Monitor(RewardConfig(kind="free", collision_penalty=0.3), dataclasses.replace(EP, end_on_collision=end))
    terms, _, _, term, flags = mon.evaluate(*args, upright, jnp.float32(0.0), jnp.float32(1.0), jnp.bool_(True))
    assert float(terms["collision"]) == pytest.approx(-0.3) and bool(flags["collided"])
    assert bool(term) == end
    terms, _, _, term, _ = mon.evaluate(*args, upright, jnp.float32(0.0), jnp.float32(1.0), NO_HIT)
    assert float(terms["collision"]) == 0.0 and not bool(term)


def test_cog_deviation_hand_cases():
  flat = cog_deviation(jnp.array([0.1, 0.0, 0.2]), jnp.zeros(3), jnp.float32(0.0))
  assert float(flat) == pytest.approx(np.hypot(0.1, 0.2))  # no incline: |(x, z)|
  theta = np.arctan2(0.17, 0.30)
  # a COG straight above the chassis origin along the incline normal, 0.1 m up
  n = np.array([-np.sin(theta), 0.0, np.cos(theta)])
  dev = cog_deviation(jnp.asarray(0.1 * n, jnp.float32), jnp.zeros(3), jnp.float32(theta))
  cx = -np.tan(theta) * 0.1
  assert float(dev) == pytest.approx(np.hypot(0.1, cx), abs=1e-6)
  assert float(cog_deviation(jnp.array([0, 0, 1.0]), jnp.zeros(3), jnp.float32(0.0))) == pytest.approx(0.32)


def test_reward_functions_and_termination():
  ep = EP
  window = jnp.array([0.1, 0.2, 0.3, 0.0, 0.4])
  upright = jnp.zeros(3)
  for kind, expected in (("free", 0.0), ("cog", -0.05 * 0.2), ("angular", -0.05 * 0.2)):
    mon = Monitor(RewardConfig(kind=kind, cog_scale=0.05, angular_scale=0.05), ep)
    terms, prog, _, term, _ = mon.evaluate(jnp.float32(1.5), jnp.float32(2.0), jnp.float32(2.0),
                                           upright, jnp.mean(window), jnp.float32(1.0), NO_HIT)
    assert float(terms["progress"]) == pytest.approx(0.25)
    assert float(terms["safety"]) == pytest.approx(expected)
    assert not bool(term)
  mon = Monitor(RewardConfig(kind="cog", cog_scale=0.05), ep)
  _, _, _, term, flags = mon.evaluate(jnp.float32(1.5), jnp.float32(2.0), jnp.float32(2.0),
                                      jnp.array([0.0, 1.7, 0.0]), jnp.mean(window), jnp.float32(1.0), NO_HIT)
  assert bool(term) and bool(flags["tipped"])
  _, _, _, term, flags = mon.evaluate(jnp.float32(-0.01), jnp.float32(2.0), jnp.float32(2.0),
                                      upright, jnp.mean(window), jnp.float32(1.0), NO_HIT)
  assert bool(term) and bool(flags["reached"])
  _, _, _, term, flags = mon.evaluate(jnp.float32(2.5), jnp.float32(2.0), jnp.float32(2.0),
                                      upright, jnp.mean(window), jnp.float32(1.0), NO_HIT)
  assert bool(term) and bool(flags["away"])  # 2.5 > 1.2 * 2.0


def test_penalty_normalization_uses_the_first_episodes():
  cfg = RewardConfig(normalize_penalties=True, normalize_episodes=3)
  s = normalizer_init(cfg)
  assert float(s.k) == 0.0  # no penalty while calibrating
  s = normalizer_update(cfg, s, jnp.array([True, False, True]), jnp.array([0.2, 9.0, 0.4]))
  assert float(s.k) == 0.0 and int(s.count) == 2
  s = normalizer_update(cfg, s, jnp.array([True, True]), jnp.array([0.6, 100.0]))
  assert float(s.k) == pytest.approx(3 / 1.2)  # 1 / mean(0.2, 0.4, 0.6); later episodes ignored
  s2 = normalizer_update(cfg, s, jnp.array([True]), jnp.array([50.0]))
  assert float(s2.k) == pytest.approx(float(s.k))
  assert float(normalizer_init(RewardConfig(normalize_penalties=False)).k) == 1.0


def test_goal_line_ignores_lateral_offset_within_its_halfwidth():
  goal = jnp.array([3.0, 0.0, 1.0])
  # 0.58 m to the side of a point goal is 0.28 m outside the tolerance; on a 1 m half-width line it is at the goal
  assert float(goal_distance(jnp.array([3.0, -0.58, 1.0]), goal, 0.0, 0.3)) == pytest.approx(0.28, abs=1e-6)
  assert bool(goal_reached(goal_distance(jnp.array([3.0, -0.58, 1.0]), goal, 1.0, 0.3)))
  # beyond the line's end the distance is measured from the end point
  d = goal_distance(jnp.array([3.0, 1.4, 1.0]), goal, 1.0, 0.3)
  assert float(d) == pytest.approx(0.1, abs=1e-6) and not bool(goal_reached(d))
  # along x the line is as far as the point
  assert float(goal_distance(jnp.array([2.0, 0.5, 1.0]), goal, 1.0, 0.3)) == pytest.approx(0.7, abs=1e-6)


def test_on_stairs_window_spans_the_staircase_plus_the_margin():
  top = jnp.float32(2.1)
  m = ON_STAIRS_MARGIN
  inside = jnp.array([-m + 0.01, 0.0, 1.0, 2.1 + m - 0.01])
  outside = jnp.array([-m - 0.01, -1.0, 2.1 + m + 0.01, 5.0])
  assert bool(jnp.all(on_stairs(inside, top))) and not bool(jnp.any(on_stairs(outside, top)))


def test_the_episode_mean_form_sums_to_the_episodes_mean_sample_whatever_its_length():
  """Per step, the change of the running mean (the newest sample first in the window); over an
  episode, the mean of its samples (hand-computed); the window form reads the window's mean."""
  samples = [0.4, 0.1, 0.0, 0.7, 0.3, 0.2, 0.5]
  mon = Monitor(RewardConfig(kind="angular", safety_form="episode_mean", safety_window=3), EP)
  window, total, rates = jnp.zeros(3), 0.0, []
  for t, x in enumerate(samples, 1):
    window, total = jnp.roll(window, 1).at[0].set(x), total + x
    rates.append(float(mon.safety_rate(window, jnp.float32(total), jnp.int32(t))))
  assert rates[0] == pytest.approx(0.4) and rates[1] == pytest.approx(0.25 - 0.4)
  assert sum(rates) == pytest.approx(np.mean(samples), abs=1e-6)
  assert sum(rates[:4]) == pytest.approx(np.mean(samples[:4]), abs=1e-6)  # an episode cut short: its own mean
  paper = Monitor(RewardConfig(kind="angular", safety_form="window", safety_window=3), EP)
  assert float(paper.safety_rate(window, jnp.float32(total), jnp.int32(7))) == pytest.approx(np.mean(samples[-3:]))


def test_reaching_the_goal_earns_the_goal_bonus_once_it_is_reached():
  mon = Monitor(RewardConfig(goal_bonus=0.5), EP)
  reached, *_ = mon.evaluate(jnp.float32(-0.01), jnp.float32(0.1), jnp.float32(2.0), jnp.zeros(3), jnp.float32(0.0),
                             jnp.float32(1.0), NO_HIT)
  short, *_ = mon.evaluate(jnp.float32(0.01), jnp.float32(0.1), jnp.float32(2.0), jnp.zeros(3), jnp.float32(0.0),
                           jnp.float32(1.0), NO_HIT)
  assert float(reached["goal"]) == 0.5 and float(short["goal"]) == 0.0

"""Terrain kinds against MuJoCo C models written out by hand from their parameters (downward rays
over a grid hit the same heights), their spawns and goals, the kind draw, the hard ends, and the
evaluation scenes that pin them."""

import dataclasses

import jax
import mujoco
import numpy as np
import pytest

from mjx_tracks.envs.config import ConfigError, load_config
from mjx_tracks.envs.task_env import make_scene
from scenes.staircase import LANDING_LENGTH, WIDTH, world_xml
from scenes.terrain import POOL
from scenes.terrain_kinds import TERRAIN_PARAMS
from scenes.world import SCENE_BOX
from train.evaluation import scene_config, suite_scenes

KINDS = tuple(k for k, p in TERRAIN_PARAMS.items() if p.corridor)  # the mixed task draws these; spirals: test_spiral.py
XI = {  # a few parameter sets per kind (their own units: m, or a count)
    "step_up": [(0.3,), (0.05,)], "step_down": [(0.4,), (0.12,)],
    "uplift": [(0.25, 0.3), (0.1, 1.4)], "rails": [(0.15, 1.2), (0.05, 0.4)],
    "waves": [(0.25, 1.0), (0.1, 2.7)], "blocks": [(0.2, 0.3), (0.05, 0.55)],
    "landing_up": [(0.35, 0.22, 10, 0.6), (0.5, 0.12, 3, 1.5), (0.4, 0.17, 7, 1.0)],
    "landing_down": [(0.35, 0.22, 10, 0.6), (0.45, 0.15, 4, 1.2)]}
C = 0.01  # m, rays stay this far from every box edge (an edge hit is either height)


def _stair_boxes(t, r, n, landing):
  """(x0, x1, y0, y1, top) of each step: step k < n - 1 is t long but step n // 2 (1-based) is
  `landing` long; the top step is the 3 m landing; tops (k + 1) r."""
  out, x = [], 0.0
  for k in range(n):
    length = LANDING_LENGTH if k == n - 1 else (landing if k == n // 2 - 1 else t)
    out.append((x, x + length, -1.0, 1.0, (k + 1) * r))
    x += length
  return out


def _oracle(kind, xi, tops=None):
  """The boxes a kind's parameters describe, written out by hand (blocks: heights given)."""
  if kind in ("step_up", "step_down"):
    return [(0.0, 3.0, -1.0, 1.0, xi[0])]
  if kind == "uplift":
    return [(0.0, xi[1], -1.0, 1.0, xi[0])]
  if kind == "rails":
    return [(k * xi[1], k * xi[1] + 0.1, -1.0, 1.0, xi[0]) for k in range(4)]
  if kind == "waves":
    seg = xi[1] / 8
    return [(k * seg, (k + 1) * seg, -1.0, 1.0, xi[0] * (1 - np.cos(2 * np.pi * (k + 0.5) / 8)) / 2) for k in range(16)]
  if kind == "blocks":
    return [(r * xi[1], (r + 1) * xi[1], -1.0 + c * 0.5, -0.5 + c * 0.5, tops[4 * r + c]) for r in range(4) for c in range(4)]
  return _stair_boxes(xi[0], xi[1], int(xi[2]), xi[3])  # landing_up, landing_down


def _c_model(boxes) -> tuple[mujoco.MjModel, mujoco.MjData]:
  geoms = "".join(f'<geom type="box" pos="{(a + b) / 2} {(c + d) / 2} {top / 2}" size="{(b - a) / 2} {(d - c) / 2} {top / 2}"/>'
                  for a, b, c, d, top in boxes)
  m = mujoco.MjModel.from_xml_string(f'<mujoco><worldbody><geom type="plane" size="0 0 1"/>{geoms}</worldbody></mujoco>')
  d = mujoco.MjData(m)
  mujoco.mj_forward(m, d)
  return m, d


def _generated_model(pos, size) -> tuple[mujoco.MjModel, mujoco.MjData]:
  """The corridor world of a terrain task with the generated boxes."""
  m = mujoco.MjModel.from_xml_string(f'<mujoco><asset><material name="world"/></asset><worldbody>{world_xml(POOL)}'
                                     '</worldbody></mujoco>')
  ids = [i for i in range(m.ngeom) if (mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, i) or "").startswith(SCENE_BOX)]
  m.geom_pos[ids], m.geom_size[ids] = np.asarray(pos), np.asarray(size)
  d = mujoco.MjData(m)
  mujoco.mj_forward(m, d)
  return m, d


def _height(m, d, x, y) -> float:
  """z (m) where a ray straight down from 5 m first hits geom group 0."""
  return 5.0 - mujoco.mj_ray(m, d, np.array([x, y, 5.0]), np.array([0.0, 0.0, -1.0]),
                             np.array([1, 0, 0, 0, 0, 0], np.uint8), 1, -1, np.zeros(1, np.int32))


def _probe_points(boxes):
  """Points inside each box and just outside its front and back (C from its edges), and on the floor
  between and around the boxes."""
  pts = []
  for a, b, c, d, _ in boxes:
    for fy in (0.0, 1.0):
      y = c + C + fy * (d - c - 2 * C)
      pts += [(a + C + fx * (b - a - 2 * C), y) for fx in (0.0, 0.5, 1.0)] + [(a - C, y), (b + C, y)]
  xs = sorted({a for a, *_ in boxes} | {b for _, b, *_ in boxes})
  pts += [((u + v) / 2, 0.3) for u, v in zip(xs, xs[1:]) if v - u > 2 * C] + [(-0.5, 0.0), (xs[-1] + 0.5, -0.2)]
  return pts


def _scene(kind):
  cfg = load_config("mixed-terrain")
  return make_scene(dataclasses.replace(cfg.scene, terrains=(kind,)))


@pytest.mark.parametrize("kind", KINDS)
def test_terrain_boxes_match_a_c_model_written_from_their_parameters(kind):
  layout = jax.jit(lambda xi, key, kind=kind: _scene(kind).layout(0, xi, key))
  for i, xi in enumerate(XI[kind]):
    pos, size, _, ends = layout(np.asarray(xi, np.float32), jax.random.PRNGKey(i))
    tops = 2 * np.asarray(size)[:16, 2] if kind == "blocks" else None
    oracle, generated = _c_model(_oracle(kind, xi, tops)), _generated_model(pos, size)
    for x, y in _probe_points(_oracle(kind, xi, tops)):
      assert _height(*generated, x, y) == pytest.approx(_height(*oracle, x, y), abs=1e-4), (kind, xi, x, y)
    used = np.asarray(pos)[:, 2] > -5
    assert used.sum() == len(_oracle(kind, xi, tops)) and (np.asarray(pos)[~used, 2] < -5).all()
    if kind == "blocks":
      assert (tops >= 0.2 * xi[0] - 1e-6).all() and (tops <= xi[0] + 1e-6).all()  # ~ U(0.2, 1) height


@pytest.mark.parametrize("kind", KINDS)
def test_spawn_and_goal_lie_before_and_past_the_terrain_at_ground_height(kind):
  xi = XI[kind][0]
  *_, e = _scene(kind).layout(0, np.asarray(xi, np.float32), jax.random.PRNGKey(0))
  boxes = _oracle(kind, xi, np.zeros(16))
  spawn, goal = np.asarray(e.spawn), np.asarray(e.goal)
  if kind in ("step_down", "landing_down"):
    top = boxes[-1]
    assert spawn == pytest.approx([top[0] + 1.0, 0.0, top[4]]) and float(e.yaw) == pytest.approx(np.pi)
    assert goal == pytest.approx([-1.0, 0.0, 0.085])
  elif kind in ("step_up", "landing_up"):
    top = boxes[-1]
    assert spawn == pytest.approx([-1.0, 0.0, 0.0]) and float(e.yaw) == 0.0
    assert goal == pytest.approx([top[0] + 1.0, 0.0, top[4] + 0.085], abs=1e-5)
  else:
    far = max(b for _, b, *_ in boxes)
    assert spawn == pytest.approx([-1.0, 0.0, 0.0]) and goal == pytest.approx([far + 1.0, 0.0, 0.085], abs=1e-5)


def test_a_mixed_task_draws_each_kind_with_equal_probability_and_records_it():
  scene = make_scene(load_config("mixed-terrain").scene)
  n = 4000
  s = jax.jit(jax.vmap(scene.sample, in_axes=(0, None)))(jax.random.split(jax.random.PRNGKey(3), n), 0.5)
  counts = np.bincount(np.asarray(s.variant), minlength=len(KINDS))
  p = 1 / len(KINDS)
  assert np.abs(counts - n * p).max() < 4 * np.sqrt(n * p * (1 - p)), counts  # binomial, 4 sigma
  assert s.xi.shape == (n, sum(len(TERRAIN_PARAMS[k].names) for k in KINDS))


@pytest.mark.parametrize("kind", KINDS)
def test_hardest_kind_pins_every_parameter_at_its_hard_end(kind):
  cfg = load_config("mixed-terrain")
  pinned = scene_config(cfg, f"hardest/{kind}")
  scene = make_scene(pinned.scene)
  assert scene.kinds == (kind,)
  s = jax.vmap(scene.sample, in_axes=(0, None))(jax.random.split(jax.random.PRNGKey(0), 8), 0.0)
  ranges = getattr(cfg.scene.terrain, kind)
  hard = [getattr(ranges, n)[end == "high"] for n, end in zip(TERRAIN_PARAMS[kind].names, TERRAIN_PARAMS[kind].hard)]
  np.testing.assert_allclose(np.asarray(s.xi), np.tile(hard, (8, 1)), rtol=1e-6)


def test_held_out_terrains_pin_their_kind_and_values_for_the_tasks_that_draw_it():
  cfg = load_config("mixed-terrain", ["evaluation.held_out_terrain=[{name: tall, kind: uplift, values: [0.4, 0.6]}]"])
  scene = make_scene(scene_config(cfg, "held-out/tall").scene)
  s = jax.vmap(scene.sample, in_axes=(0, None))(jax.random.split(jax.random.PRNGKey(0), 4), 0.3)
  assert scene.kinds == ("uplift",) and np.allclose(np.asarray(s.xi), [[0.4, 0.6]] * 4)
  assert suite_scenes(load_config("waves", ["evaluation.held_out_terrain=[{name: tall, kind: uplift, values: [0.4, 0.6]}]"])) \
      == ["hardest", "uniform"]  # a kind the task does not draw
  with pytest.raises(ConfigError, match="names \\['tall'\\]"):
    scene_config(cfg, "held-out/short")
  with pytest.raises(ConfigError, match=r"evaluation.held_out_terrain\[0\].values: uplift takes \['height', 'length'\]"):
    load_config("uplift", ["evaluation.held_out_terrain=[{name: a, kind: uplift, values: [0.3]}]"])
  with pytest.raises(ConfigError, match="length must be in"):
    load_config("uplift", ["evaluation.held_out_terrain=[{name: a, kind: uplift, values: [0.3, 9.0]}]"])


def test_terrain_suites_and_bad_terrain_settings():
  held = {k: [f"held-out/{h.name}" for h in load_config("uplift").evaluation.held_out_terrain if h.kind == k] for k in KINDS}
  assert suite_scenes(load_config("uplift")) == ["hardest", "uniform", *held["uplift"]] and held["uplift"]
  assert suite_scenes(load_config("mixed-terrain")) == ["hardest", "uniform", *(f"hardest/{k}" for k in KINDS),
                                                       *(h for k in KINDS for h in held[k])]
  with pytest.raises(ConfigError, match="draws terrains"):
    scene_config(load_config("uplift"), "hardest/waves")
  with pytest.raises(ConfigError, match="scene.terrains"):
    load_config("uplift", ["scene.terrains=[ramp]"])
  with pytest.raises(ConfigError, match="scene.terrain.waves.amplitude"):
    load_config("waves", ["scene.terrain.waves.amplitude=[0.3, 0.1]"])
  with pytest.raises(ConfigError, match="held-out staircases need a stair task"):
    load_config("uplift", ["evaluation.held_out=[{name: a, tread: 0.3, riser: 0.2, steps: 3}]"])
  assert WIDTH == 2.0  # the oracle's corridor: y in [-1, 1], blocks 0.5 m across

"""Batched staircase geometry against a MuJoCo C model built directly from xi; rays; distinct scenes."""

import dataclasses

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
import pytest
from mujoco import mjx

import mjx_tracks

from mjx_tracks.envs.config import default_config, load_config
from mjx_tracks.envs.task_env import make_scene
from scenes.navigation import AREA_W
from scenes.staircase import LANDING_LENGTH
from scenes.world import SCENE_BOX


def _stairs(**kw):
  """The default staircase scene, sampled uniformly, with scene-section overrides."""
  return make_scene(dataclasses.replace(default_config().scene, sampler="uniform", **kw))


def _c_model_from_xi(l: float, h: float, n: int) -> tuple[mujoco.MjModel, mujoco.MjData]:
  """Independent oracle: one box per step written out by hand from (l, h, n), after mj_forward."""
  geoms = []
  for k in range(n):
    length = LANDING_LENGTH if k == n - 1 else l
    geoms.append(f'<geom type="box" pos="{k * l + length / 2} 0 {(k + 1) * h / 2}" '
                 f'size="{length / 2} 1 {(k + 1) * h / 2}"/>')
  c = mujoco.MjModel.from_xml_string(f"<mujoco><worldbody>{''.join(geoms)}</worldbody></mujoco>")
  d = mujoco.MjData(c)
  mujoco.mj_forward(c, d)
  return c, d


@pytest.fixture(scope="module")
def batch(jaguar_stairs):
  """32 uniform staircases placed into the compiled model, after MJX kinematics."""
  sim = jaguar_stairs
  scene = _stairs()
  keys = jax.random.split(jax.random.PRNGKey(7), 32)

  def one(key):
    s = scene.sample(key, 0.0)
    m = sim.with_boxes(s.box_pos, s.box_size)
    d = mjx.kinematics(m, mjx.make_data(m, impl="jax"))
    xs = (jnp.arange(7) + 0.5) * s.xi[0]
    rays = jax.vmap(lambda x: mjx.ray(m, d, jnp.array([x, 0.3, 5.0]), jnp.array([0.0, 0, -1]),
                                      geomgroup=(1, 0, 0, 0, 0, 0))[0])(xs)
    return s, d.geom_xpos[sim.layout.scene_boxes], m.geom_size[sim.layout.scene_boxes], rays

  return jax.jit(jax.vmap(one))(keys)


def test_step_boxes_sit_where_xi_says(batch):
  s, xpos, size, _ = batch
  for i in range(xpos.shape[0]):
    l, h, n = (float(s.xi[i, 0]), float(s.xi[i, 1]), int(s.xi[i, 2]))
    c, d = _c_model_from_xi(l, h, n)
    np.testing.assert_allclose(np.asarray(xpos[i, :n]), d.geom_xpos, atol=1e-5)
    np.testing.assert_allclose(np.asarray(size[i, :n]), c.geom_size, atol=1e-5)
    assert (np.asarray(xpos[i, n:, 2]) < -5).all()  # unused steps parked below the floor


def test_ray_straight_down_over_each_tread_hits_its_height(batch):
  s, _, _, rays = batch
  for i in range(rays.shape[0]):
    l, h, n = (float(s.xi[i, 0]), float(s.xi[i, 1]), int(s.xi[i, 2]))
    c, d = _c_model_from_xi(l, h, n)
    for k in range(n):
      expected = 5.0 - (k + 1) * h
      gid = np.zeros(1, np.int32)
      oracle = mujoco.mj_ray(c, d, np.array([(k + 0.5) * l, 0.3, 5.0]), np.array([0.0, 0, -1]),
                             None, 1, -1, gid)
      assert float(rays[i, k]) == pytest.approx(expected, abs=1e-4)
      assert oracle == pytest.approx(expected, abs=1e-6)


def test_one_key_resets_256_distinct_staircases():
  scene = _stairs()
  s = jax.jit(jax.vmap(scene.sample, in_axes=(0, None)))(jax.random.split(jax.random.PRNGKey(0), 256), 0.0)
  xi = np.asarray(s.xi)
  assert len({tuple(row) for row in xi.round(6)}) == 256


def test_spawn_and_goal_follow_the_geometry():
  up = _stairs(direction="up")
  down = _stairs(direction="down")
  key = jax.random.PRNGKey(3)
  su, sd = up.sample(key, 0.0), down.sample(key, 0.0)
  l, h, n = (float(x) for x in su.xi)
  np.testing.assert_allclose(np.asarray(su.goal), [(n - 1) * l + 1.0, 0, n * h + 0.085], atol=1e-5)
  np.testing.assert_allclose(np.asarray(su.spawn_pos), [-1.0, 0, 0], atol=1e-6)
  np.testing.assert_allclose(np.asarray(sd.spawn_pos), [(n - 1) * l + 1.0, 0, n * h], atol=1e-5)
  assert float(sd.spawn_yaw) == pytest.approx(np.pi)
  np.testing.assert_allclose(np.asarray(sd.goal), [-1.0, 0, 0.085], atol=1e-6)


def test_random_spawn_stays_in_its_area():
  scene = _stairs(random_spawn=True, random_goal=True)
  s = jax.vmap(scene.sample, in_axes=(0, None))(jax.random.split(jax.random.PRNGKey(1), 2000), 0.0)
  y, yaw = np.asarray(s.spawn_pos[:, 1]), np.asarray(s.spawn_yaw)
  assert np.abs(y).max() <= 0.75 and np.abs(y).max() > 0.7
  assert np.abs(yaw).max() <= np.pi / 2 and np.abs(yaw).max() > 1.5


def test_navigation_kinds_are_equally_likely_and_leave_a_gap():
  scene = make_scene(dataclasses.replace(load_config("nav").scene, random_spawn=True, random_goal=True))
  s = jax.jit(jax.vmap(scene.sample, in_axes=(0, None)))(jax.random.split(jax.random.PRNGKey(2), 4000), 0.0)
  kind = np.asarray(s.variant)
  assert abs(kind.mean() - 0.5) < 0.03
  w1, w2, c = (np.asarray(s.xi[:, i]) for i in (0, 2, 4))
  assert ((c >= 1.0) & (c <= 2.0)).all()
  hall, zig = kind == 0, kind == 1
  assert (AREA_W - w1[hall] - w2[hall] >= c[hall] - 1e-4).all()  # hallway at least C wide
  assert (w1[zig] >= AREA_W / 2 - c[zig] / 2 - 1e-4).all() and (AREA_W - w1[zig] >= c[zig] - 1e-4).all()
  # zigzag walls jut from alternating sides and together span at least W - C of the width
  assert (w1[zig] + w2[zig] >= AREA_W - c[zig] - 1e-4).all()


def test_floor_obstacles_lie_in_the_obstacle_area_with_their_drawn_sizes_and_heights():
  # each layout as drawn (nav_floor_passage 0: not conditioned on a way round, which skews positions)
  scene = make_scene(load_config("nav-obstacles", ["scene.nav_floor_passage=0"]).scene)
  n = scene.floor_obstacles
  s = jax.jit(jax.vmap(scene.sample, in_axes=(0, None)))(jax.random.split(jax.random.PRNGKey(5), 500), 0.0)
  pos, size = np.asarray(s.box_pos[:, 2:]), np.asarray(s.box_size[:, 2:])
  assert pos.shape == (500, n, 3)
  for lo, hi, x in ((2.5, 9.5, pos[..., 0]), (-4.5, 4.5, pos[..., 1]), (0.15, 0.4, size[..., 0]), (0.15, 0.4, size[..., 1]),
                    (0.05, 0.15, 2 * size[..., 2])):
    assert x.min() >= lo - 1e-5 and x.max() <= hi + 1e-5
    assert abs(x.mean() - (lo + hi) / 2) < 0.02 * (hi - lo) + 1e-3  # U(lo, hi): mean within 2 % of the range
  np.testing.assert_allclose(pos[..., 2], size[..., 2])  # resting on the floor
  sim = mjx_tracks.load("nav-obstacles").sim
  c = sim.c_model_with_boxes(s.box_pos[0], s.box_size[0])
  d = mujoco.MjData(c)
  mujoco.mj_forward(c, d)
  all_pos, all_size = np.asarray(s.box_pos[0]), np.asarray(s.box_size[0])
  for k in range(n):  # a ray straight down onto each obstacle's centre hits the top of the tallest box there
    x, y = pos[0, k, :2]
    top = 5.0 - mujoco.mj_ray(c, d, np.array([x, y, 5.0]), np.array([0.0, 0, -1]),
                              np.array([1, 0, 0, 0, 0, 0], np.uint8), 1, -1, np.zeros(1, np.int32))
    over = (np.abs(all_pos[:, 0] - x) <= all_size[:, 0]) & (np.abs(all_pos[:, 1] - y) <= all_size[:, 1])
    assert top == pytest.approx((all_pos[over, 2] + all_size[over, 2]).max(), abs=1e-5)


def test_a_long_staircase_task_sizes_its_box_pool_and_places_every_step():
  """Up to 15 steps (the pool sized by the task, 7 for the paper's): boxes against the C model
  built from xi, and rays straight down over each tread (MJX ray) hitting its height."""
  from scenes.staircase import MAX_STEPS
  assert _stairs().n_boxes == 7 and MAX_STEPS == 15
  scene = _stairs(steps=(10, 15))
  assert scene.n_boxes == 15
  dof = '<body pos="0 0 -30"><joint type="slide"/><geom size=".01" contype="0" conaffinity="0"/></body>'  # MJX needs one
  xml = f'<mujoco><asset><material name="world"/></asset><worldbody>{scene.world_xml()}{dof}</worldbody></mujoco>'
  c_model = mujoco.MjModel.from_xml_string(xml)
  boxes = np.array([mujoco.mj_name2id(c_model, mujoco.mjtObj.mjOBJ_GEOM, f"{SCENE_BOX}{k}") for k in range(15)])
  assert (boxes >= 0).all()
  m = mjx.put_model(c_model, impl="jax")

  @jax.jit
  def one(key):
    s = scene.sample(key, 0.0)
    mm = m.replace(geom_pos=m.geom_pos.at[boxes].set(s.box_pos), geom_size=m.geom_size.at[boxes].set(s.box_size))
    d = mjx.kinematics(mm, mjx.make_data(mm, impl="jax"))
    xs = (jnp.arange(15) + 0.5) * s.xi[0]
    rays = jax.vmap(lambda x: mjx.ray(mm, d, jnp.array([x, 0.3, 5.0]), jnp.array([0.0, 0, -1]))[0])(xs)
    return s, rays

  lengths = set()
  for key in jax.random.split(jax.random.PRNGKey(3), 6):
    s, rays = one(key)
    l, h, n = float(s.xi[0]), float(s.xi[1]), int(s.xi[2])
    lengths.add(n)
    c, d = _c_model_from_xi(l, h, n)
    np.testing.assert_allclose(np.asarray(s.box_pos[:n]), d.geom_xpos, atol=1e-5)
    np.testing.assert_allclose(np.asarray(s.box_size[:n]), c.geom_size, atol=1e-5)
    assert (np.asarray(s.box_pos[n:, 2]) < -5).all()
    np.testing.assert_allclose(np.asarray(rays[:n]), 5.0 - (np.arange(n) + 1) * h, atol=1e-4)
  assert 10 <= min(lengths) and max(lengths) <= 15 and len(lengths) > 1


def _turning_radius(sim) -> float:
  """The largest horizontal distance (m) of any robot geom's bounding-box corner from the chassis,
  robot 1 at rest in MuJoCo's C model (joints at 0): the circle its footprint sweeps turning in place."""
  c = sim.mj_model
  d = mujoco.MjData(c)
  mujoco.mj_forward(c, d)
  centre = d.xpos[sim.layout.chassis_body][:2]
  corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
  reach = 0.0
  for g in range(c.ngeom):
    if c.geom_bodyid[g] == 0:  # the world's geoms
      continue
    local = c.geom_aabb[g, :3] + corners * c.geom_aabb[g, 3:]
    world = d.geom_xpos[g] + local @ d.geom_xmat[g].reshape(3, 3).T
    reach = max(reach, np.linalg.norm(world[:, :2] - centre, axis=1).max())
  return reach


@pytest.mark.parametrize("gap", [(0.85, 0.85), (1.0, 2.0), (3.0, 3.0)])
def test_every_nav_spawn_leaves_room_to_turn_in_place(gap):
  """A robot that cannot reverse must be able to turn where it starts: the circle its footprint
  sweeps clears the area's walls and both wall obstacles at every random spawn, in either area."""
  env = mjx_tracks.load("nav", [f"scene.nav_gap=[{gap[0]}, {gap[1]}]"])
  radius = _turning_radius(env.sim)
  assert 0.55 < radius < 0.75  # robot 1 at rest: 0.62 m (its arm stretched flat ahead: 0.75 m)
  s = jax.jit(jax.vmap(env.scene.sample, in_axes=(0, None)))(jax.random.split(jax.random.PRNGKey(7), 20000), 1.0)
  p = np.asarray(s.spawn_pos[:, None, :2])
  lo = np.asarray(s.box_pos[:, :2, :2] - s.box_size[:, :2, :2])
  hi = np.asarray(s.box_pos[:, :2, :2] + s.box_size[:, :2, :2])
  to_box = np.linalg.norm(np.maximum(0.0, np.maximum(lo - p, p - hi)), axis=-1).min(axis=1)
  x, y = p[:, 0, 0], p[:, 0, 1]
  to_wall = np.minimum.reduce([x, AREA_W / 2 - y, y + AREA_W / 2])
  assert np.minimum(to_box, to_wall).min() > radius + 0.15  # 0.8 m by design: room for the arm stretched too
  assert set(np.unique(np.asarray(s.variant))) == {0, 1}

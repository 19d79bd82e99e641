"""Collision watch (mjx_tracks.sim.collisions) against the MuJoCo C engine's contacts, in the
navigation world: the robot against a wall obstacle (any part counts), over a floor obstacle on its
belts (does not count) and with its belly on one (counts)."""

import functools

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
import pytest
from mujoco import mjx

import mjx_tracks
from mjx_tracks.sim import mjx_private
from scenes.navigation import AREA_W

ROBOT_Y = 0.0  # m; the robot stands at x = 6 m, heading +x (unless a case moves it along y)
HIDDEN = ([-20.0, 0.0, -5.0], [0.1, 0.1, 0.1])  # a box out of the way (m)


def _c_collisions(watch, m: mujoco.MjModel, d: mujoco.MjData) -> set:
  """The geom pairs (sorted) of the C engine's contacts that the module docstring's rule counts,
  read off its contact list in plain Python."""
  pairs = set()
  for k in range(d.ncon):
    c = d.contact[k]
    if c.dist - c.includemargin >= 0:
      continue
    for world, part in ((c.geom1, c.geom2), (c.geom2, c.geom1)):
      if m.geom_bodyid[part] > 0 and (watch.forbidden[world] or (watch.belts_only[world] and not watch.belt[part])):
        pairs.add(tuple(sorted((int(c.geom1), int(c.geom2)))))
  return pairs


def _poses():
  """(name, expected collision, boxes (centres, half-sizes), the robot's y (m))."""
  wall = lambda gap: ([6.0, ROBOT_Y + 0.405 + gap + 0.5, 0.5], [1.0, 0.5, 0.5])  # wall obstacle's face gap m beyond y = 0.405 (flippers: pivot 0.315 + radius 0.09)
  floor = lambda y, h: ([6.0, y, h / 2], [0.08, 0.06, h / 2])  # a floor obstacle (box 2) under the robot
  cases = [(f"wall obstacle, face {g:+.2f} m beyond the flippers' side", g < 0, [wall(g), HIDDEN, HIDDEN], ROBOT_Y)
           for g in (-0.1, -0.04, 0.03, 0.1)]
  cases += [("floor obstacle under the left track", False, [HIDDEN, HIDDEN, floor(0.3, 0.03)], ROBOT_Y),
            ("floor obstacle under the belly", True, [HIDDEN, HIDDEN, floor(0.0, 0.09)], ROBOT_Y),
            ("floor obstacle the belly clears (its bottom: 0.055 m)", False, [HIDDEN, HIDDEN, floor(0.0, 0.04)], ROBOT_Y),
            ("left wall plane 0.03 m inside the flippers", True, [HIDDEN] * 3, AREA_W / 2 - 0.405 + 0.03),
            ("left wall plane 0.03 m beyond the flippers", False, [HIDDEN] * 3, AREA_W / 2 - 0.405 - 0.03)]
  return cases


@functools.lru_cache(maxsize=None)
def _watched():
  """(env, jitted flag(qpos, box centres, box half-sizes) per robot: whether it collides, which
  contacts are collisions, every contact's geom pair): one program for every test."""
  env = mjx_tracks.load("nav-obstacles", ["scene.nav_floor_obstacles=1"])

  def flag(q, p, s):
    m = env.sim.with_boxes(p, s)
    d = mjx.forward(m, mjx.make_data(m, impl="jax").replace(qpos=q))
    return env.watch.touching(d), env.watch.colliding(d), mjx_private.contacts(d).geom, env.watch.riding(d)

  return env, jax.jit(jax.vmap(flag))


def test_collision_flag_matches_the_c_engine_contacts_and_the_rule():
  env, flags = _watched()
  sim, watch = env.sim, env.watch
  assert watch.forbidden.sum() == 6 and watch.belts_only.sum() == 1  # 4 walls + 2 obstacles; 1 floor obstacle
  cases = _poses()
  qpos = []
  for _, _, boxes, y in cases:
    qpos.append(np.asarray(sim.init_data(jnp.array([6.0, y, 0.0]), jnp.float32(0.0)).qpos))
  pos = jnp.array([[b[0] for b in boxes] for _, _, boxes, _ in cases])
  size = jnp.array([[b[1] for b in boxes] for _, _, boxes, _ in cases])
  got, which, geoms, riding = map(np.asarray, flags(jnp.asarray(np.stack(qpos)), pos, size))
  assert [name for (name, *_), r in zip(cases, riding) if r] == ["floor obstacle under the left track"]
  for (name, expected, boxes, _), q, g, w, pairs, r in zip(cases, qpos, got, which, geoms, riding):
    m = sim.c_model_with_boxes(np.array([b[0] for b in boxes]), np.array([b[1] for b in boxes]))
    d = mujoco.MjData(m)
    d.qpos[:] = q
    mujoco.mj_forward(m, d)
    oracle = _c_collisions(watch, m, d)
    assert bool(g) == bool(oracle) == expected, name
    assert {tuple(sorted(map(int, p))) for p in pairs[w]} == oracle, name  # the same geom pairs
    on_belts = any(c.dist - c.includemargin < 0 and any(watch.belts_only[a] and watch.belt[b] for a, b in
                                                       ((c.geom1, c.geom2), (c.geom2, c.geom1))) for c in d.contact[:d.ncon])
    assert bool(r) == on_belts, name  # riding: a belt on a floor obstacle, as the C engine's contacts say


def test_stair_and_terrain_worlds_watch_nothing():
  for task in ("asc-inc-cog", "step-up"):
    assert not mjx_tracks.load(task).watch.active



def test_no_random_spawn_starts_touching_a_wall_or_obstacle():
  env, flags = _watched()
  n = len(_poses())  # the other test's batch: the same program
  scenes = jax.jit(jax.vmap(env.scene.sample, in_axes=(0, None)))(jax.random.split(jax.random.PRNGKey(3), 64 * n), 1.0)
  qpos = jax.jit(jax.vmap(lambda p, y: env.sim.init_data(p, y).qpos))(scenes.spawn_pos, scenes.spawn_yaw)
  hits = [np.asarray(flags(qpos[k:k + n], scenes.box_pos[k:k + n], scenes.box_size[k:k + n])[0]) for k in range(0, 64 * n, n)]
  assert not np.concatenate(hits).any()


def test_footprint_clearance_reads_the_hand_derived_gap_and_zero_where_the_c_engine_sees_a_collision():
  """The footprint (robot 1: flipper capsules of radius 0.075 m at y = +-0.315 m, their tips at
  x = +-(0.4 + 0.105) m) against the wall-obstacle and wall-plane cases of _poses(): its clearance
  is the face's distance beyond y = 0.39 m (0 inside), and 0 in every case the C engine collides."""
  env, _ = _watched()
  assert env.footprint == pytest.approx((0.505, 0.39))
  state = jax.jit(env.scene.sample)(jax.random.PRNGKey(0), 1.0)
  clearance = jax.jit(lambda scene, pos, yaw: env.kind.clearance(env.scene, scene, pos, yaw, jnp.array(env.footprint)))
  for name, collides, boxes, y in _poses():
    if "floor" in name:
      continue
    face = boxes[0][0][1] - boxes[0][1][1] if boxes[0] is not HIDDEN else AREA_W / 2  # m, the near face's y
    scene = state.replace(box_pos=jnp.array([b[0] for b in boxes]), box_size=jnp.array([b[1] for b in boxes]))
    got = float(clearance(scene, jnp.array([6.0, y, 0.2]), jnp.float32(0.0)))
    assert got == pytest.approx(max(face - y - 0.39, 0.0), abs=1e-5), name
    assert (got == 0.0) == collides, name
  # turned by 90 degrees at the area's back wall (x = 0): the flipper tips face the side walls, the side the back wall
  scene = state.replace(box_pos=jnp.array([HIDDEN[0]] * 2), box_size=jnp.array([HIDDEN[1]] * 2))
  got = clearance(scene, jnp.array([0.5, 0.0, 0.2]), jnp.float32(np.pi / 2))
  assert float(got) == pytest.approx(0.5 - 0.39, abs=1e-5)

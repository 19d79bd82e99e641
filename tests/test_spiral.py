"""Spiral staircases: yawed boxes in MJX and in the C model against the spiral's definition in polar
coordinates (downward rays over every tread's sector hit its height; beside the stairs, the floor),
their spawns and goals, their open world, hard ends and settings."""

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
import pytest
from mujoco import mjx

from mjx_tracks.envs.config import ConfigError, load_config
from mjx_tracks.envs.task_env import make_scene
from scenes.terrain_kinds import TERRAIN_PARAMS
from train.evaluation import scene_config

XI = [(3.0, 0.2, 0.15, 6), (2.5, 0.25, 0.12, 5)]  # radius m, angle rad, riser m, steps (<= 7: the shared simulator's pool)


def _polar(radius, r, phi):
  """(x, y) at distance r from the spiral's axis (0, radius), angle phi from its start."""
  return r * np.sin(phi), radius - r * np.cos(phi)


def _on_landing(radius, end, s, lateral):
  """(x, y) s m along the landing (which starts at angle end) and lateral m to its left."""
  x, y = _polar(radius, radius, end)
  return x + s * np.cos(end) - lateral * np.sin(end), y + s * np.sin(end) + lateral * np.cos(end)


def _probes(xi):
  """(x, y, height) the definition gives: tread k at (k + 1) riser across its sector's middle, the
  floor 0.3 m beyond either edge, the landing at steps x riser, the floor past it and before the stairs."""
  radius, angle, riser, n = xi
  pts = []
  for k in range(n - 1):
    phi = (k + 0.5) * angle
    pts += [(*_polar(radius, r, phi), (k + 1) * riser) for r in (radius - 0.5, radius, radius + 0.9)]
    pts += [(*_polar(radius, r, phi), 0.0) for r in (radius - 1.3, radius + 1.3)]
  end = (n - 1) * angle
  pts += [(*_on_landing(radius, end, s, lat), n * riser) for s in (0.3, 1.5, 2.7) for lat in (-0.8, 0.0, 0.8)]
  return pts + [(*_on_landing(radius, end, 3.3, 0.0), 0.0), (-0.5, 0.0, 0.0)]


def _layout(kind, xi):
  scene = make_scene(load_config(kind.replace("_", "-")).scene)
  return scene.layout(0, jnp.asarray(xi, jnp.float32), jax.random.PRNGKey(0))


@pytest.mark.parametrize("xi", XI)
def test_spiral_treads_in_mjx_and_the_c_model_lie_where_the_polar_definition_puts_them(jaguar_stairs, xi):
  sim = jaguar_stairs
  pos, size, yaw, _ = _layout("spiral_up", xi)
  n = len(sim.layout.scene_boxes)
  assert (np.asarray(pos)[n:, 2] < -5).all()  # the rest of the pool is parked
  m = sim.with_boxes(pos[:n], size[:n], yaw[:n])
  d = mjx.kinematics(m, mjx.make_data(m, impl="jax"))
  pts = _probes(xi)
  starts = jnp.asarray([(x, y, 5.0) for x, y, _ in pts], jnp.float32)
  ray = jax.jit(jax.vmap(lambda p: mjx.ray(m, d, p, jnp.array([0.0, 0, -1]), geomgroup=(1, 0, 0, 0, 0, 0))[0]))
  c = sim.c_model_with_boxes(pos[:n], size[:n], yaw[:n])
  cd = mujoco.MjData(c)
  mujoco.mj_forward(c, cd)
  for (x, y, z), dist in zip(pts, np.asarray(ray(starts))):
    assert 5.0 - dist == pytest.approx(z, abs=1e-4), (xi, x, y, z)
    c_dist = mujoco.mj_ray(c, cd, np.array([x, y, 5.0]), np.array([0.0, 0, -1]), np.array([1, 0, 0, 0, 0, 0], np.uint8),
                           1, -1, np.zeros(1, np.int32))
    assert 5.0 - c_dist == pytest.approx(z, abs=1e-4), (xi, x, y, z)


def test_spiral_spawns_and_point_goals_lie_on_the_centre_line_before_the_stairs_and_on_the_landing():
  radius, angle, riser, n = xi = XI[0]
  end = (n - 1) * angle
  landing = np.array([*_on_landing(radius, end, 1.0, 0.0), n * riser])
  *_, up = _layout("spiral_up", xi)
  *_, down = _layout("spiral_down", xi)
  np.testing.assert_allclose(up.spawn, [-1.0, 0, 0], atol=1e-6)
  np.testing.assert_allclose(up.goal, landing + [0, 0, 0.085], atol=1e-5)
  np.testing.assert_allclose(down.spawn, landing, atol=1e-5)
  assert float(down.yaw) == pytest.approx(end + np.pi) and float(up.yaw) == 0.0
  np.testing.assert_allclose(down.goal, [-1.0, 0, 0.085], atol=1e-6)
  assert float(up.goal_halfwidth) == float(down.goal_halfwidth) == 0.0  # a point: the robot steers


def test_spirals_stand_in_the_open_and_their_hardest_scene_pins_every_hard_end():
  cfg = load_config("spiral-up")
  assert "wall_left" not in make_scene(cfg.scene).world_xml()
  assert "wall_left" in make_scene(load_config("step-up").scene).world_xml()
  scene = make_scene(scene_config(cfg, "hardest").scene)
  s = jax.vmap(scene.sample, in_axes=(0, None))(jax.random.split(jax.random.PRNGKey(0), 8), 0.0)
  ranges, p = cfg.scene.terrain.spiral_up, TERRAIN_PARAMS["spiral_up"]
  hard = [getattr(ranges, n)[end == "high"] for n, end in zip(p.names, p.hard)]
  np.testing.assert_allclose(np.asarray(s.xi), np.tile(hard, (8, 1)), rtol=1e-6)
  assert np.abs(np.asarray(s.box_yaw)).max() > 0.1


def test_bad_spiral_settings_name_their_key():
  with pytest.raises(ConfigError, match="scene.terrains: mixes corridor kinds with spirals"):
    load_config("spiral-up", ["scene.terrains=[spiral_up, step_up]"])
  with pytest.raises(ConfigError, match=r"scene.terrain.spiral_down: at \[.*\]: \(steps - 1\) x angle = 3.5 rad"):
    load_config("spiral-down", ["scene.terrain.spiral_down.angle=[0.2, 0.25]", "scene.terrain.spiral_down.steps=[3, 15]"])
  with pytest.raises(ConfigError, match=r"evaluation.held_out_terrain\[0\].values: \(steps - 1\)"):
    load_config("spiral-up", ["evaluation.held_out_terrain=[{name: a, kind: spiral_up, values: [3, 0.5, 0.1, 9]}]"])
  for key in ("random_spawn", "random_goal"):
    with pytest.raises(ConfigError, match=rf"scene.{key}: not supported by \['spiral_up'\]"):
      load_config("spiral-up", [f"scene.{key}=true"])

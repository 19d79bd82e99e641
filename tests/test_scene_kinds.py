"""The scene-kind registry (scenes.kinds): every invalid combination is refused when the config
loads, in one line naming the key; no scene-kind name is compared outside the registry."""

import pathlib
import re

import pytest

from mjx_tracks.envs.config import REWARD_SIGNALS, ConfigError, available_tasks, load_config
from scenes.kinds import SCENE_KINDS, scene_kind

ROOT = pathlib.Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("task, override, key, words", [
    ("asc-inc-cog", "robot=2", "control.mode", "drives the arm"),  # robot 2 has no arm
    ("asc-inc-cog", "control.mode=3dof_stairs", "observation.parts", None),  # fine: robot 1 has an arm
    ("asc-inc-cog-r2", "observation.parts=[v, arm]", "observation.parts", "'arm' needs a robot with an arm"),
    ("asc-inc-cog", "control.v_range=[0, 9]", "control.v_range", "must lie inside"),
    ("step-up", "reward.kind=cog", "reward.kind", "terrain scenes do not measure"),
    ("nav", "reward.kind=cog", "reward.kind", "nav scenes do not measure"),
    ("nav", "scene.nav_kinds=[maze]", "scene.nav_kinds", "areas of ['hallway', 'zigzag']"),
    ("nav", "scene.nav_kinds=[zigzag, zigzag]", "scene.nav_kinds", "distinct"),
    ("nav", "control.mode=5dof_stairs", "control.mode", "angular velocity w"),
    ("step-up", "scene.terrains=[lava]", "scene.terrains", "non-empty list"),
    ("spiral-up", "scene.random_goal=true", "scene.random_goal", "centre line"),
    ("step-up", "evaluation.held_out=[{name: a, tread: 0.4, riser: 0.2, steps: 3}]", "evaluation.held_out", "stair task"),
    ("asc-inc-cog", "scene.kind=lava", "scene.kind", "must be one of ['stairs', 'terrain', 'nav']"),
    ("asc-inc-cog", "episode.distance=geodesic", "episode.distance", "stairs scenes measure ['euclidean']"),
    ("nav", "episode.distance=manhattan", "episode.distance", "must be one of ['euclidean', 'geodesic']"),
    ("step-up", "episode.end_on_collision=true", "episode.end_on_collision", "nothing to collide with"),
    ("asc-inc-cog", "reward.collision_penalty=0.5", "reward.collision_penalty", "nothing to collide with"),
    ("nav", "reward.progress_form=greedy", "reward.progress_form", "must be one of ['closest', 'potential']"),
])
def test_invalid_combinations_are_refused_at_load_naming_the_key(task, override, key, words):
  if words is None:
    load_config(task, [override])  # the control case loads
    return
  with pytest.raises(ConfigError) as e:
    load_config(task, [override])
  assert e.value.key == key and str(e.value).startswith(f"{key}: ") and words in str(e.value)
  assert "\n" not in str(e.value)


def test_every_task_loads_and_its_kind_measures_its_rewards_signal():
  for task in available_tasks():
    cfg = load_config(task)
    signal = REWARD_SIGNALS[cfg.reward.kind]
    assert signal is None or signal in scene_kind(cfg.scene.kind).signals, task


def test_every_kinds_suite_names_scenes_it_can_pin():
  from train.evaluation import scene_config, suite_scenes
  for task in available_tasks():
    cfg = load_config(task)
    for scene in suite_scenes(cfg):
      assert scene_config(cfg, scene).scene.kind == cfg.scene.kind, (task, scene)


def test_no_scene_kind_name_is_compared_outside_the_registry():
  """`kind == "stairs"`, `.kind != 'nav'`, `kind in ("stairs", ...)` appear only under scenes/kinds/."""
  names = "|".join(SCENE_KINDS)
  compared = re.compile(rf"""(==|!=)\s*["']({names})["']|["']({names})["']\s*(==|!=)|in \(["']({names})["']""")
  found = [f"{p.relative_to(ROOT)}:{i}" for folder in ("mjx_tracks", "scenes", "train")
           for p in (ROOT / folder).rglob("*.py") if "kinds" not in p.parent.name
           for i, line in enumerate(p.read_text().splitlines(), 1) if compared.search(line)]
  assert not found


def test_held_out_navigation_areas_narrow_the_gap_or_add_obstacles_and_stay_passable():
  import jax
  import numpy as np
  from mjx_tracks.envs.task_env import make_scene
  cfg = load_config("nav")
  kind = scene_kind("nav")
  assert [s for s in kind.suite(cfg) if s.startswith("held-out/")] == ["held-out/narrow-gap", "held-out/dense-obstacles",
                                                                       "held-out/long-area"]
  narrow, dense = (make_scene(kind.pinned(cfg, f"held-out/{n}").scene) for n in ("narrow-gap", "dense-obstacles"))
  assert dense.floor_obstacles == 12 and narrow.floor_obstacles == 0
  s = jax.jit(jax.vmap(narrow.sample, in_axes=(0, None)))(jax.random.split(jax.random.PRNGKey(0), 200), 0.5)
  np.testing.assert_allclose(np.asarray(s.xi[:, 4]), 0.9, atol=1e-6)  # C, m
  free = jax.jit(jax.vmap(narrow.free_space_distance))(s, s.spawn_pos)
  assert np.isfinite(np.asarray(free)).all()  # a path for the robot's clearance remains
  with pytest.raises(ConfigError, match=r"evaluation.held_out_nav\[0\].gap: needs 0.85"):
    load_config("nav", ["evaluation.held_out_nav=[{name: slit, gap: [0.5, 0.5], floor_obstacles: 0, length: 12}]"])
  with pytest.raises(ConfigError, match="held-out areas"):
    kind.pinned(cfg, "held-out/middle")


def test_a_longer_held_out_area_moves_its_obstacles_goal_and_front_wall_and_lengthens_the_episode():
  import jax
  import mujoco
  import numpy as np
  from mjx_tracks.envs.task_env import TrackedRobotEnv
  cfg = load_config("nav-obstacles")
  long_cfg = scene_kind("nav").pinned(cfg, "held-out/long-area")
  assert long_cfg.scene.nav_length == 18.0 and long_cfg.episode.max_steps == 360  # 240 x 18 / 12
  env = TrackedRobotEnv(long_cfg)
  s = jax.vmap(env.scene.sample, in_axes=(0, None))(jax.random.split(jax.random.PRNGKey(0), 200), 1.0)
  goal, lo, hi = np.asarray(s.goal), np.asarray(s.box_pos - s.box_size), np.asarray(s.box_pos + s.box_size)
  assert (goal[:, 0] >= 16.5).all() and (goal[:, 0] <= 17.5).all() and goal[:, 0].max() > 17.3  # U(A - 1.5, A - 0.5)
  walls = slice(0, 2)  # the wall obstacles stay in the obstacle area [2, A - 2] and reach past the 12 m area's
  assert (lo[:, walls, 0] >= 2 - 1e-5).all() and (hi[:, walls, 0] <= 16 + 1e-5).all() and hi[:, walls, 0].max() > 12
  zig = np.asarray(s.variant) == 1  # zigzag walls at 2 + L/3 and 2 + 2L/3, L = A - 4 = 14 m
  np.testing.assert_allclose(np.asarray(s.box_pos[zig, :2, 0]), np.broadcast_to([2 + 14 / 3, 2 + 28 / 3], (zig.sum(), 2)), atol=1e-5)
  assert np.isfinite(np.asarray(jax.vmap(env.scene.free_space_distance)(s, s.spawn_pos))).all()
  data = mujoco.MjData(env.sim.mj_model)  # the compiled world: a ray along +x from x = 17 m meets the front wall 1 m on
  mujoco.mj_forward(env.sim.mj_model, data)
  dist = mujoco.mj_ray(env.sim.mj_model, data, np.array([17.0, 0.0, 0.5]), np.array([1.0, 0.0, 0.0]),
                       np.array([1, 0, 0, 0, 0, 0], np.uint8), 1, -1, np.zeros(1, np.int32))
  np.testing.assert_allclose(dist, 1.0, atol=1e-6)
  assert scene_kind("nav").pinned(cfg, "held-out/narrow-gap").episode.max_steps == 240  # same length: same episode


def test_each_kind_names_the_scene_its_probes_and_success_early_stops_run_on():
  from scenes.kinds.base import SceneKind
  assert [load_config(t).scene.probe_scene for t in ("asc-inc-cog", "mixed-terrain", "nav")] == ["hardest", "hardest", "uniform"]
  assert SceneKind().probe_scene(load_config("nav").scene) is None  # a kind with no hardest configuration: no probe

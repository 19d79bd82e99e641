"""Task configs: every task loads; unknown keys, wrong types and bad values fail naming the key."""

import pathlib
import re

import pytest

from mjx_tracks.envs.config import ConfigError, available_tasks, config_dir, default_config, from_dict, load_config

PAPER_TASKS = {"asc-inc-cog", "asc-uni-cog", "des-inc-ang", "des-uni-ang"}


def test_registry_holds_the_papers_tasks_and_more():
  tasks = set(available_tasks())
  assert PAPER_TASKS <= tasks and "nav" in tasks and "asc-inc-free" in tasks


@pytest.mark.parametrize("task", sorted(PAPER_TASKS))
def test_paper_tasks_use_robot_1_five_dof_and_sixty_vertical_beams(task):
  cfg = load_config(task)
  assert cfg.robot == "1" and cfg.control.mode == "5dof_stairs"
  assert cfg.observation.parts == ("v", "flippers_paired", "arm", "pitch", "vertical_beams")
  assert cfg.observation.vertical_beams == 60
  assert cfg.scene.sampler == ("incremental" if "-inc-" in task else "uniform")
  assert cfg.reward.kind == ("cog" if task.startswith("asc") else "angular")


def test_overrides_apply_and_are_typed():
  cfg = load_config("asc-inc-cog", ["reward.cog_scale=0.5", "scene.tread=[0.4, 0.5]"])
  assert cfg.reward.cog_scale == 0.5 and cfg.scene.tread == (0.4, 0.5)


@pytest.mark.parametrize("override,message", [
    ("reward.cog_scal=0.5", "reward.cog_scal: unknown key"),
    ("rewards.cog_scale=0.5", "rewards: unknown key"),
    ("reward.cog_scale=abc", "reward.cog_scale: must be a number"),
    ("episode.max_steps=2.5", "episode.max_steps: must be an integer"),
    ("scene.steps=[1, 16]", "scene.steps: needs 1 <= min <= max <= 15"),
    ("control.mode=3dof", "control.mode: must be one of"),
    ("scene.curriculum.rule=median", "scene.curriculum.rule"),
    ("physics.timestep=0.3", "physics.timestep"),
    ("control.period=0.255", "control.period: must be a multiple"),
    ("reward.cog_scale", "expected KEY=VALUE"),
    ("control.dof_curriculum=[[arm, 0.5]]", "control.dof_curriculum: 'arm' is not a joint dimension"),
    ("control.dof_curriculum=[[v, 0.5]]", "control.dof_curriculum: 'v' is not a joint dimension"),
    ("control.dof_curriculum=[[front, 0.2], [front, 0.4]]", "control.dof_curriculum: 'front' must appear once"),
    ("control.dof_curriculum=[[rear, 1.5]]", "control.dof_curriculum: 'rear' must appear once with an eps in"),
    ("control.dof_curriculum=[[rear]]", "control.dof_curriculum[0]: must have 2 entries"),
])
def test_bad_values_fail_naming_the_key(override, message):
  with pytest.raises(ConfigError, match=message.replace("[", r"\[")):
    load_config("asc-inc-cog", [override])


def test_unknown_task_lists_the_known_ones():
  with pytest.raises(ConfigError, match="unknown task 'flying'.*asc-inc-cog"):
    load_config("flying")


def test_defaults_file_is_not_a_task_and_holds_every_key():
  assert "defaults" not in available_tasks()
  with pytest.raises(ConfigError, match="unknown task 'defaults'"):
    load_config("defaults")
  cfg = default_config()  # every dataclass field must have its default there, or this fails
  assert cfg.scene.variant == "difficulty" and cfg.observation.parts == load_config("asc-inc-cog").observation.parts


def test_the_yaml_is_read_beside_the_package_that_runs_installed_or_from_a_checkout(tmp_path):
  """Installed: the package data mjx_tracks/configs; a source checkout: the repository's configs/,
  whichever checkout an editable install maps the package data to; neither: one line saying so."""
  installed, checkout = tmp_path / "site" / "mjx_tracks", tmp_path / "repo" / "mjx_tracks"
  for folder in (installed / "configs", checkout.parent / "configs"):
    folder.mkdir(parents=True)
    (folder / "defaults.yaml").write_text("{}")
  checkout.mkdir()
  assert config_dir(installed) == installed / "configs" and config_dir(checkout) == checkout.parent / "configs"
  with pytest.raises(FileNotFoundError, match="no defaults.yaml in .* the install is incomplete"):
    config_dir(tmp_path / "bare" / "mjx_tracks")
  import mjx_tracks
  assert config_dir() == pathlib.Path(mjx_tracks.__file__).resolve().parents[1] / "configs"  # this checkout's


def test_a_run_config_missing_a_key_names_it():
  raw = load_config("asc-inc-cog").to_dict()
  del raw["physics"]["impratio"]
  with pytest.raises(ConfigError, match=r"physics: missing keys \['impratio'\]"):
    from_dict(raw)


def test_a_run_config_from_before_contact_culling_keeps_every_contact():
  """run.json files written before physics.contact_slots / box_pairs existed load with -1 (all
  contacts, what those runs simulated), not with today's defaults."""
  raw = load_config("asc-inc-cog").to_dict()
  assert raw["physics"]["contact_slots"] > 0 and raw["physics"]["box_pairs"] > 0
  for key in ("contact_slots", "box_pairs"):
    del raw["physics"][key]
  physics = from_dict(raw).physics
  assert (physics.contact_slots, physics.box_pairs) == (-1, -1)


def test_a_run_config_from_before_terrains_gets_none_drawn_and_todays_held_out_terrains():
  """Terrain keys missing from an older run.json: no kinds drawn, the default ranges, and (an
  evaluation-only key) today's held-out terrains."""
  raw = load_config("uplift").to_dict()
  for section, key in (("scene", "terrains"), ("scene", "terrain"), ("evaluation", "held_out_terrain")):
    del raw[section][key]
  raw["scene"]["kind"] = "stairs"
  cfg = from_dict(raw)
  today = load_config("uplift")
  assert cfg.scene.terrains == () and cfg.scene.terrain == today.scene.terrain
  assert cfg.evaluation.held_out_terrain == today.evaluation.held_out_terrain != ()


def test_a_terrain_run_config_from_before_spirals_gets_their_default_ranges_and_keeps_its_own():
  raw = load_config("uplift", ["scene.terrain.uplift.height=[0.1, 0.2]"]).to_dict()
  del raw["scene"]["terrain"]["spiral_up"], raw["scene"]["terrain"]["spiral_down"]
  cfg = from_dict(raw)
  assert cfg.scene.terrain.spiral_up == load_config("spiral-up").scene.terrain.spiral_up
  assert cfg.scene.terrain.uplift.height == (0.1, 0.2) and "spiral_up" not in raw["scene"]["terrain"]  # raw untouched


def test_renamed_curriculum_variants_say_their_new_names():
  with pytest.raises(ConfigError, match="'original' is now 'original_code'"):
    load_config("asc-inc-cog", ["scene.variant=original"])


def test_hardest_scene_pins_every_parameter_at_its_hard_end():
  from train.evaluation import scene_config
  s = scene_config(load_config("asc-inc-cog", ["scene.tread=[0.4, 0.5]"]), "hardest").scene
  assert (s.tread, s.riser, s.steps, s.sampler) == ((0.4, 0.4), (0.22, 0.22), (7, 7), "uniform")
  with pytest.raises(ConfigError, match="navigation tasks have no hardest"):
    scene_config(load_config("nav"), "hardest")


def test_nav_suites_evaluate_each_area_kind_alone():
  import jax
  from mjx_tracks.envs.task_env import make_scene
  from train.evaluation import scene_config, suite_scenes
  cfg = load_config("nav")
  held_out = [f"held-out/{h.name}" for h in cfg.evaluation.held_out_nav]
  assert held_out == ["held-out/narrow-gap", "held-out/dense-obstacles", "held-out/long-area"]
  assert suite_scenes(cfg) == ["uniform", "nav/hallway", "nav/zigzag", *held_out]
  assert suite_scenes(load_config("nav", ["scene.nav_kinds=[zigzag]"])) == ["uniform", *held_out]
  for variant, kind in enumerate(("hallway", "zigzag")):
    scene = make_scene(scene_config(cfg, f"nav/{kind}").scene)
    s = jax.vmap(scene.sample, in_axes=(0, None))(jax.random.split(jax.random.PRNGKey(0), 16), 0.5)
    assert (s.variant == variant).all()
  with pytest.raises(ConfigError, match=r"draws navigation areas \['zigzag'\]"):
    scene_config(load_config("nav", ["scene.nav_kinds=[zigzag]"]), "nav/hallway")
  with pytest.raises(ConfigError, match=r"nav/KIND is not for stair tasks"):
    scene_config(load_config("asc-inc-cog"), "nav/hallway")
  bare = "evaluation.held_out_nav=[{name: bare-zigzag, gap: [1.0, 2.0], floor_obstacles: 0, length: 12.0, areas: [zigzag]}]"
  s = scene_config(load_config("nav-obstacles", [bare]), "held-out/bare-zigzag").scene  # one area kind, no floor boxes
  assert (s.nav_kinds, s.nav_floor_obstacles) == (("zigzag",), 0)
  assert scene_config(load_config("nav-obstacles"), "held-out/narrow-gap").scene.nav_kinds == ("hallway", "zigzag")
  with pytest.raises(ConfigError, match=r"held_out_nav\[0\].areas: must be distinct areas of the task's \['zigzag'\]"):
    load_config("nav", ["scene.nav_kinds=[zigzag]", bare.replace("[zigzag]", "[hallway]")])
  with pytest.raises(ConfigError, match=r"held_out_nav\[0\].areas"):
    load_config("nav", [bare.replace("[zigzag]", "[zigzag, zigzag]")])


def test_held_out_scenes_pin_their_staircase_and_bad_ones_are_named():
  from train.evaluation import scene_config, suite_scenes
  cfg = load_config("asc-inc-cog", ["evaluation.held_out=[{name: low, tread: 0.5, riser: 0.12, steps: 2}]"])
  s = scene_config(cfg, "held-out/low").scene
  assert (s.tread, s.riser, s.steps, s.sampler) == ((0.5, 0.5), (0.12, 0.12), (2, 2), "uniform")
  assert suite_scenes(cfg) == ["hardest", "uniform", "held-out/low"]
  with pytest.raises(ConfigError, match="names \\['low'\\]"):
    scene_config(cfg, "held-out/high")
  with pytest.raises(ConfigError, match=r"evaluation.held_out\[0\].steps: must be in \[1, 15\]"):
    load_config("asc-inc-cog", ["evaluation.held_out=[{name: x, tread: 0.5, riser: 0.12, steps: 16}]"])
  with pytest.raises(ConfigError, match="names repeat"):
    load_config("asc-inc-cog", ["evaluation.held_out=[{name: x, tread: 0.5, riser: 0.1, steps: 2}, "
                                "{name: x, tread: 0.4, riser: 0.1, steps: 2}]"])
  with pytest.raises(ConfigError, match="need a stair task"):
    load_config("nav", ["evaluation.held_out=[{name: x, tread: 0.5, riser: 0.1, steps: 2}]"])


def test_a_recorded_config_from_before_the_evaluation_section_loads_without_held_out_scenes():
  raw = load_config("asc-inc-cog").to_dict()
  del raw["evaluation"]
  assert from_dict(raw).evaluation.held_out == ()


def test_a_recorded_nav_config_from_before_collision_safety_loads_with_the_papers_monitor():
  raw = load_config("nav").to_dict()
  for section, key in (("reward", "progress_form"), ("reward", "collision_penalty"), ("episode", "distance"),
                       ("episode", "end_on_collision"), ("scene", "nav_gap"), ("evaluation", "held_out_nav")):
    del raw[section][key]
  cfg = from_dict(raw)
  assert (cfg.reward.progress_form, cfg.reward.collision_penalty, cfg.episode.distance) == ("closest", 0.0, "euclidean")
  assert not cfg.episode.end_on_collision and tuple(cfg.scene.nav_gap) == (1.0, 2.0)
  assert [h.name for h in cfg.evaluation.held_out_nav] == ["narrow-gap", "dense-obstacles", "long-area"]  # today's


def test_declared_ranges_are_what_validation_checks_and_what_the_form_shows():
  from mjx_tracks.bounds import Bound
  from train.server.schema import schema
  assert [Bound(1, 480).contains(v) for v in (0, 1, 480, 481)] == [False, True, True, False]
  assert [Bound(0.0, 1.0, hi_open=True).contains(v) for v in (0.0, 0.999, 1.0)] == [True, True, False]
  assert [Bound(1.0, lo_open=True).contains(v) for v in (1.0, 1.0001)] == [False, True]
  assert (Bound(1, 480).text(), Bound(0, 1, hi_open=True).text(), Bound(0).text(), Bound(1, lo_open=True).text()) == (
      "[1, 480]", "[0, 1)", ">= 0", "> 1")
  fields = {f["key"]: f for s in schema("asc-inc-cog") for f in s["fields"]}
  assert (fields["episode.max_steps"]["range"], fields["episode.max_steps"]["default"]) == ("[1, 100000]", 50)
  assert fields["physics.timestep"]["range"] == "[0.0005, 0.02]" and fields["physics.timestep"]["note"] == "s"
  assert fields["scene.curriculum.window"]["range"] == ">= 1" and fields["scene.sampler"]["range"] == ""
  for key, f in fields.items():  # each declared range is the one validation enforces, at both ends
    if f["range"].startswith("["):
      lo, hi = (float(x) for x in f["range"].strip("[]()").split(","))
      for bad in (lo - 1, hi + 1):
        bad = int(bad) if f["kind"] == "int" else bad
        with pytest.raises(ConfigError, match=re.escape(key)):
          load_config("asc-inc-cog", [f"{key}={bad}"])


@pytest.mark.parametrize("depth", [200, 5_000])
def test_deeply_nested_yaml_is_refused_in_one_line_whichever_layer_stops_it(depth):
  """PyYAML >= 6.0.4 refuses deep nesting itself; older ones recurse until Python's limit: the
  message is the same either way (and a study posted to the server says it too)."""
  from mjx_tracks.envs.config import NESTED_TOO_DEEPLY, load_yaml
  text = "a: " + "[" * depth + "]" * depth
  if depth == 200:  # shallow enough for every parser: read as nested lists
    value = load_yaml(text, "x.yaml")["a"]
    for _ in range(depth - 1):
      (value,) = value
    assert value == []
    return
  with pytest.raises(ConfigError) as e:
    load_yaml(text, "x.yaml", "study")
  assert str(e.value) == f"x.yaml: {NESTED_TOO_DEEPLY}" and e.value.key == "study"


def test_a_parser_that_limits_the_depth_itself_gets_the_same_message(monkeypatch):
  """PyYAML >= 6.0.4's own refusal ("exceeded maximum nesting depth"), whichever PyYAML is installed."""
  import yaml

  from mjx_tracks.envs import config

  class Refusing:
    def __init__(self, text):
      pass

    def get_single_node(self):
      raise yaml.MarkedYAMLError(problem="exceeded maximum nesting depth")

    def dispose(self):
      pass

  monkeypatch.setattr(config, "SAFE_LOADER", Refusing)
  with pytest.raises(ConfigError) as e:
    config.load_yaml("a: 1", "x.yaml")
  assert str(e.value) == f"x.yaml: {config.NESTED_TOO_DEEPLY}"

"""2D navigation areas (scenes.navigation lays them out): hallway or zigzag, with optional low
floor obstacles; xi = the two wall obstacles' extents and the gap."""

from __future__ import annotations

import dataclasses
import math

from scenes.kinds.base import HARDEST, HELD_OUT, NAV, SceneKind, no_held_out_staircases, replace_scene
from scenes.navigation import NAV_AREAS


def longer_episode(cfg, factor: float):
  """cfg with its episodes `factor` times as long (rounded up to whole control steps): a held-out area
  that much longer than the task's own gets the time to cross it."""
  if factor == 1:
    return cfg
  steps = math.ceil(cfg.episode.max_steps * factor)
  return dataclasses.replace(cfg, episode=dataclasses.replace(cfg.episode, max_steps=steps))


class Nav(SceneKind):
  name = "nav"
  camera = "overhead"
  signals = ("pitch_rate", "collision", "clearance")
  distances = ("euclidean", "geodesic")
  parameters = ("scene.nav_kinds (areas drawn), scene.nav_floor_obstacles, scene.nav_floor_height, "
                "scene.nav_floor_passage, scene.nav_length")

  def validate(self, cfg) -> None:
    from mjx_tracks.envs.config import require  # noqa: PLC0415
    from mjx_tracks.sim.control import CONTROL_MODES  # noqa: PLC0415
    areas = cfg.scene.nav_kinds
    require(bool(areas) and all(a in NAV_AREAS for a in areas) and len(set(areas)) == len(areas),
            "scene.nav_kinds", lambda: f"must be a non-empty list of distinct areas of {list(NAV_AREAS)}, got {list(areas)}")
    require("w" in CONTROL_MODES[cfg.control.mode], "control.mode", "navigation needs a mode with angular velocity w")
    for i, h in enumerate(cfg.evaluation.held_out_nav):
      require(all(a in areas for a in h.areas) and len(set(h.areas)) == len(h.areas),
              f"evaluation.held_out_nav[{i}].areas",
              lambda h=h: f"must be distinct areas of the task's {list(areas)} (or [] for all), got {list(h.areas)}")
    no_held_out_staircases(cfg)

  drawn = ("sampler", "nav_kinds")  # uniform and each area alone: one program (held-out areas change more)

  def draw(self, s, program):
    from scenes.navigation import UNIT  # noqa: PLC0415
    from scenes.samplers import as_draw  # noqa: PLC0415
    return as_draw(UNIT, s.sampler, [a in s.nav_kinds for a in program.nav_kinds])

  def make(self, s):
    from scenes.navigation import NavScene  # noqa: PLC0415
    return NavScene(s.sampler, s.variant, s.nav_kinds, s.random_spawn, s.random_goal, s.nav_floor_obstacles,
                    s.nav_floor_height, s.nav_gap, s.nav_clearance, s.nav_floor_passage, s.nav_length)

  def suite(self, cfg) -> list[str]:
    areas = cfg.scene.nav_kinds
    return ["uniform", *((NAV + a for a in areas) if len(areas) > 1 else ()),
            *(HELD_OUT + h.name for h in cfg.evaluation.held_out_nav)]

  def pinned(self, cfg, scene: str):
    from mjx_tracks.envs.config import ConfigError  # noqa: PLC0415
    if scene.startswith(NAV):
      area = scene[len(NAV):]
      if area not in cfg.scene.nav_kinds:
        raise ConfigError(f"scene {scene!r}: the task draws navigation areas {list(cfg.scene.nav_kinds)}")
      return replace_scene(cfg, nav_kinds=(area,))
    if scene.startswith(HELD_OUT):
      held = {h.name: h for h in cfg.evaluation.held_out_nav}
      h = held.get(scene[len(HELD_OUT):])
      if h is None:
        raise ConfigError(f"scene {scene!r}: the task's held-out areas (evaluation.held_out_nav) are {list(held)}")
      return longer_episode(replace_scene(cfg, nav_gap=tuple(h.gap), nav_floor_obstacles=h.floor_obstacles,
                                          nav_length=h.length, nav_kinds=tuple(h.areas) or cfg.scene.nav_kinds),
                            h.length / cfg.scene.nav_length)
    if scene == "hardest" or scene.startswith(HARDEST):
      raise ConfigError(f"scene {scene!r}: navigation tasks have no hardest configuration; "
                        f"use uniform, {NAV}AREA or {HELD_OUT}NAME")
    return None

  def probe_scene(self, s) -> str:
    """Random areas of every kind the task draws (no area is harder than another by a parameter)."""
    return "uniform"

  def collision_geoms(self, scene):
    return scene.collision_geoms()

  def clearance(self, scene, state, pos, yaw, half):
    return scene.wall_clearance(state, pos, yaw, half)

  def groups(self, s) -> tuple[str, ...]:
    return tuple(s.nav_kinds)

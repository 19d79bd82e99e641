"""Terrains of the kinds in scenes.terrain_kinds (step, uplift, rails, waves, blocks, landings,
spirals), one drawn per episode (scenes.terrain lays them out)."""

from __future__ import annotations

import dataclasses

from scenes.kinds.base import HARDEST, HELD_OUT, NAV, SceneKind, no_held_out_staircases, replace_scene
from scenes.terrain_kinds import TERRAIN_PARAMS, corridor_world


def _ranges(s, kinds: tuple[str, ...], own=None):
  """The sampler ranges of xi for the given kinds, each kind's from section own where it draws it,
  else from section s."""
  from scenes.terrain import terrain_ranges  # noqa: PLC0415
  own = s if own is None else own
  return terrain_ranges(kinds, {k: dataclasses.asdict(getattr((own if k in own.terrains else s).terrain, k))
                                for k in kinds})


def pinned_terrain(cfg, kind: str, values):
  """The task with every episode on terrain `kind` with its parameters pinned to values (in the
  kind's order)."""
  s = cfg.scene
  ranges = dataclasses.replace(getattr(s.terrain, kind), **{n: (v, v) for n, v in zip(TERRAIN_PARAMS[kind].names, values)})
  return replace_scene(cfg, sampler="uniform", terrains=(kind,), terrain=dataclasses.replace(s.terrain, **{kind: ranges}))


def hardest_terrain(cfg, kinds: tuple[str, ...]):
  """The task drawing the given kinds, each with every parameter at its hard end."""
  for kind in kinds:
    ranges = getattr(cfg.scene.terrain, kind)
    cfg = pinned_terrain(cfg, kind, TERRAIN_PARAMS[kind].hardest(lambda n, r=ranges: getattr(r, n)))
  return replace_scene(cfg, terrains=kinds)


class Terrain(SceneKind):
  name = "terrain"
  parameters = "scene.terrains (the kinds drawn); scene.terrain.KIND.PARAM ranges"

  def has_hardest(self, s) -> bool:
    return True

  def validate(self, cfg) -> None:
    from mjx_tracks.envs.config import require  # noqa: PLC0415
    kinds = cfg.scene.terrains
    require(bool(kinds) and all(k in TERRAIN_PARAMS for k in kinds), "scene.terrains",
            f"a terrain task needs a non-empty list of {list(TERRAIN_PARAMS)}, got {list(kinds)}")
    require(len(set(kinds)) == len(kinds), "scene.terrains", f"has duplicates: {list(kinds)}")
    try:
      in_the_open = not corridor_world(kinds)
    except ValueError as e:
      require(False, "scene.terrains", str(e))
    for field in ("random_spawn", "random_goal"):
      require(not (in_the_open and getattr(cfg.scene, field)), f"scene.{field}",
              f"not supported by {list(kinds)}: spawns and goals lie on the stairs' centre line")
    no_held_out_staircases(cfg)

  drawn = ("sampler", "terrains", "terrain")  # every evaluation scene of a terrain task: one program

  def make(self, s):
    from scenes.terrain import TerrainScene  # noqa: PLC0415
    return TerrainScene(s.terrains, s.sampler, s.variant, _ranges(s, s.terrains), s.random_spawn, s.random_goal)

  def draw(self, s, program):
    """In the program's xi layout (its kinds): s's ranges for the kinds s draws (only those allowed),
    the program's for the others."""
    from scenes.samplers import as_draw  # noqa: PLC0415
    ranges = _ranges(program, program.terrains, own=s)
    return as_draw(ranges, s.sampler, [k in s.terrains for k in program.terrains])

  def held_out(self, cfg) -> dict:
    """The task's held-out terrains of the kinds it draws, by name."""
    return {h.name: h for h in cfg.evaluation.held_out_terrain if h.kind in cfg.scene.terrains}

  def suite(self, cfg) -> list[str]:
    s = cfg.scene
    return ["hardest", "uniform", *((HARDEST + k for k in s.terrains) if len(s.terrains) > 1 else ()),
            *(HELD_OUT + name for name in self.held_out(cfg))]

  def pinned(self, cfg, scene: str):
    from mjx_tracks.envs.config import ConfigError  # noqa: PLC0415
    if scene == "hardest":
      return hardest_terrain(cfg, cfg.scene.terrains)
    if scene.startswith(HARDEST):
      kind = scene[len(HARDEST):]
      if kind not in cfg.scene.terrains:
        raise ConfigError(f"scene {scene!r}: the task draws terrains {list(cfg.scene.terrains)}")
      return hardest_terrain(cfg, (kind,))
    if scene.startswith(HELD_OUT):
      named = self.held_out(cfg)
      h = named.get(scene[len(HELD_OUT):])
      if h is None:
        raise ConfigError(f"scene {scene!r}: the task's evaluation.held_out_terrain (of the kinds it draws) "
                          f"names {sorted(named) or 'none'}")
      return pinned_terrain(cfg, h.kind, h.values)
    if scene.startswith(NAV):
      raise ConfigError(f"scene {scene!r}: {NAV}AREA is for navigation tasks")
    return None

  def groups(self, s) -> tuple[str, ...]:
    return tuple(s.terrains)

"""The registry of scene kinds: `SCENE_KINDS[name]` (configs: scene.kind).

Adding a kind: a module here with a `SceneKind` subclass (scenes.kinds.base says what it
declares), its scene generator in scenes/, its keys and default ranges in configs/defaults.yaml,
and one line below.
"""

from __future__ import annotations

from scenes.kinds.base import COMMON_SCENES, HARDEST, HELD_OUT, NAV, SceneKind
from scenes.kinds.nav import Nav
from scenes.kinds.stairs import Stairs
from scenes.kinds.terrain import Terrain

SCENE_KINDS: dict[str, SceneKind] = {k.name: k for k in (Stairs(), Terrain(), Nav())}


def parameter_limits() -> dict[str, str]:
  """{dotted config key of a scene parameter's [min, max] range: what its generator supports, its
  unit and hard end}, for the staircase's and every terrain kind's parameters (the dashboard's form)."""
  from scenes.terrain_kinds import STAIRS, TERRAIN_PARAMS  # noqa: PLC0415
  tables = {"scene.": STAIRS, **{f"scene.terrain.{k}.": p for k, p in TERRAIN_PARAMS.items()}}
  return {prefix + n: f"{lo:g} to {hi:g} {p.unit(n)}".rstrip() + f", hardest {'high' if end == 'high' else 'low'}"
          for prefix, p in tables.items() for n, (lo, hi), end in zip(p.names, p.limits, p.hard)}


def scene_kind(name: str) -> SceneKind:
  """The registered kind of that name (KeyError naming the known ones)."""
  if name not in SCENE_KINDS:
    raise KeyError(f"unknown scene kind {name!r}; known: {list(SCENE_KINDS)}")
  return SCENE_KINDS[name]


__all__ = ["parameter_limits", "COMMON_SCENES", "HARDEST", "HELD_OUT", "NAV", "SCENE_KINDS", "SceneKind", "scene_kind"]

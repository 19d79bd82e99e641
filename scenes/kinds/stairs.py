"""Straight staircases, up or down (scenes.staircase lays them out): xi = (tread m, riser m, steps)."""

from __future__ import annotations

import dataclasses

from scenes.kinds.base import HARDEST, HELD_OUT, NAV, SceneKind, replace_scene
from scenes.terrain_kinds import STAIRS

EARLY_STOP_RETURN = {"up": 0.5, "down": 0.6}  # the paper's thresholds, by stair direction


def _pinned(cfg, values) -> object:
  """The task with every episode on one staircase: values in STAIRS.names order."""
  return replace_scene(cfg, sampler="uniform", **{n: (v, v) for n, v in zip(STAIRS.names, values)})


class Stairs(SceneKind):
  name = "stairs"
  signals = ("pitch_rate", "cog_deviation", "on_stairs")
  parameters = "scene.tread, scene.riser, scene.steps ranges; scene.direction up | down"
  stair_script = True
  drawn = ("sampler", "tread", "riser", "steps", "direction")  # every evaluation scene of a stair task: one program

  def has_hardest(self, s) -> bool:
    return True

  def make(self, s):
    from scenes.staircase import StairScene, stair_ranges  # noqa: PLC0415
    return StairScene(s.direction, s.sampler, s.variant, stair_ranges(s.tread, s.riser, s.steps),
                      s.random_spawn, s.random_goal)

  def draw(self, s, program):
    import jax.numpy as jnp  # noqa: PLC0415
    from scenes.samplers import as_draw  # noqa: PLC0415
    from scenes.staircase import stair_ranges  # noqa: PLC0415
    return as_draw(stair_ranges(s.tread, s.riser, s.steps), s.sampler).replace(ascent=jnp.bool_(s.direction == "up"))

  def program_section(self, task, sections):
    """The task's section, its ranges widened to hold every section's (its box pool: the most steps)."""
    def envelope(name):
      return min(getattr(s, name)[0] for s in sections), max(getattr(s, name)[1] for s in sections)
    return dataclasses.replace(task, **{n: envelope(n) for n in STAIRS.names})

  def suite(self, cfg) -> list[str]:
    return ["hardest", "uniform", *(HELD_OUT + h.name for h in cfg.evaluation.held_out)]

  def pinned(self, cfg, scene: str):
    from mjx_tracks.envs.config import ConfigError  # noqa: PLC0415
    if scene == "hardest":  # each parameter at its hard end: n = n_max, l = l_min, h = h_max
      return _pinned(cfg, STAIRS.hardest(lambda n: getattr(cfg.scene, n)))
    if scene.startswith(HELD_OUT):
      named = {h.name: h for h in cfg.evaluation.held_out}
      h = named.get(scene[len(HELD_OUT):])
      if h is None:
        raise ConfigError(f"scene {scene!r}: the task's evaluation.held_out names {sorted(named) or 'none'}")
      return _pinned(cfg, [getattr(h, n) for n in STAIRS.names])
    if scene.startswith((HARDEST, NAV)):
      raise ConfigError(f"scene {scene!r}: {scene.split('/')[0]}/KIND is not for stair tasks")
    return None

  def early_stop_return(self, s) -> float | None:
    return EARLY_STOP_RETURN[s.direction]

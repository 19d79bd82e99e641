"""What a scene kind declares, in one place: its parameters, its world, spawn and goal (its scene
generator), its evaluation scenes, its safety signals and its validation. `scenes.kinds` holds the
registry; config loading, the env, evaluation, early stopping, rendering and study reports ask
the kind of a task (`scene_kind(cfg.scene.kind)`) instead of comparing its name.

Evaluation scene names: `uniform`, `incremental` and `train` exist for every kind (the task's
ranges drawn uniformly, by the incremental sampler, or by the task's own sampler); a kind adds
its own: `hardest` (every parameter at its hard end), HELD_OUT + NAME (a fixed configuration of the
task's evaluation section), HARDEST + KIND (one sub-kind alone at its hardest), NAV + AREA (one
navigation area alone).
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

if TYPE_CHECKING:
  from mjx_tracks.envs.config import SceneConfig, TaskConfig

HELD_OUT = "held-out/"  # scene name prefix of a fixed held-out configuration (evaluation.held_out[_terrain])
HARDEST = "hardest/"  # scene name prefix of one terrain kind alone at its hardest (terrain tasks)
NAV = "nav/"  # scene name prefix of one navigation area kind alone (nav tasks)
COMMON_SCENES = ("uniform", "incremental", "train")  # evaluation scenes of every kind


class SceneKind:
  """A scene kind; subclasses override what differs. Nothing on an instance changes."""

  name: str = ""
  camera: str = "follow"  # mjx_tracks.tools.render: "follow" (behind the robot) | "overhead"
  signals: tuple[str, ...] = ("pitch_rate",)  # safety signals its scenes measure (metric names; `clearance`:
  #                                             the footprint's distance from walls, clearance() below)
  distances: tuple[str, ...] = ("euclidean",)  # goal distances it measures (episode.distance; config.DISTANCES)
  parameters: str = ""  # one line for the README / dashboard: what its xi holds
  stair_script: bool = False  # whether the stair script (the `scripted` baseline, mjx_tracks.baselines) fits it
  drawn: tuple[str, ...] = ()  # scene-section keys its generator also takes as data (draw): evaluation scenes
  #                              that differ only in these share one compiled program (train.evaluation)

  def collision_geoms(self, scene) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """Geom names of its world that (any part of the robot, any part but a track belt) must not
    touch: a contact counts as a collision (the `collision` metric). scene: its generator (make())."""
    return (), ()

  def clearance(self, scene, state, pos, yaw, half):
    """() m: the robot's footprint (centre pos, yaw rad, half-sizes half m) from the nearest wall
    (where "clearance" is among its signals). scene: its generator; state: the episode's SceneState."""
    raise NotImplementedError(f"{self.name} scenes measure no clearance")

  def has_hardest(self, s: SceneConfig) -> bool:
    """Whether its scenes have a hardest configuration (every parameter at its hard end)."""
    return False

  def probe_scene(self, s: SceneConfig) -> str | None:
    """The evaluation scene of in-training probes and of `--early-stop success` (train.core.probe):
    the hardest configuration where its scenes have one; None: no probe."""
    return "hardest" if self.has_hardest(s) else None

  def validate(self, cfg: TaskConfig) -> None:
    """ConfigError (naming the key) for any part of cfg this kind cannot run."""

  def make(self, s: SceneConfig):
    """The scene generator (world_xml(), sample(key, eps) -> SceneState) of a scene section."""
    raise NotImplementedError

  def draw(self, s: SceneConfig, program: SceneConfig):
    """The `drawn` keys of scene section s as data (a scenes.samplers.Draw) for the generator of
    section `program` (program_section): its sample(key, eps, draw); None where the kind takes none."""
    return None

  def program_section(self, task: SceneConfig, sections: list[SceneConfig]) -> SceneConfig:
    """The scene section of one program that draws each of sections from its draw; sections equal
    task but for `drawn` (task: theirs with the task's own values there). Default: task."""
    return task

  def suite(self, cfg: TaskConfig) -> list[str]:
    """The evaluation scenes of a study's suite."""
    return ["uniform"]

  def pinned(self, cfg: TaskConfig, scene: str) -> TaskConfig | None:
    """The task with every episode drawn as one of this kind's own evaluation scenes says
    (hardest, HELD_OUT + NAME, ...); None if `scene` is none of them; ConfigError if it is
    malformed for this task."""
    return None

  def early_stop_return(self, s: SceneConfig) -> float | None:
    """The paper's return threshold for early stopping, where the paper gives one."""
    return None

  def groups(self, s: SceneConfig) -> tuple[str, ...]:
    """The sub-kinds its scenes draw (terrain kinds, navigation areas), for per-kind reports."""
    return ()


def replace_scene(cfg: TaskConfig, **changes) -> TaskConfig:
  """cfg with its scene section changed."""
  return dataclasses.replace(cfg, scene=dataclasses.replace(cfg.scene, **changes))


def no_held_out_staircases(cfg: TaskConfig) -> None:
  """ConfigError unless the task names no held-out staircase (they need a stair task)."""
  from mjx_tracks.envs.config import require  # noqa: PLC0415
  require(not cfg.evaluation.held_out, "evaluation.held_out", "held-out staircases need a stair task; set []")

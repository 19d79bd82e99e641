"""Typed task configuration: configs/defaults.yaml <- configs/TASK.yaml <- dotted overrides.

Every section is a frozen dataclass; loading checks each key exists, each value's type, and each
range, and fails with a message that names the dotted key.
"""

from __future__ import annotations

import dataclasses
import pathlib
import typing
from typing import Any

import yaml

CONFIG_DIR = pathlib.Path(__file__).resolve().parent.parent / "configs"


class ConfigError(ValueError):
  """A configuration key, type or value is wrong; the message names it."""


def _check(cond: bool, key: str, msg: str) -> None:
  if not cond:
    raise ConfigError(f"{key}: {msg}")


@dataclasses.dataclass(frozen=True)
class ControlConfig:
  mode: str = "5dof_stairs"  # 4dof | 5dof_stairs | 6dof | 8dof
  increments: bool = True  # the original's +-pi/10 increments, else absolute targets
  v_range: tuple[float, float] = (0.0, 1.0)  # m/s
  period: float = 0.25  # s between actions

  def validate(self, key: str) -> None:
    from mjx_tracks.control import CONTROL_MODES  # noqa: PLC0415
    _check(self.mode in CONTROL_MODES, f"{key}.mode", f"must be one of {sorted(CONTROL_MODES)}, got {self.mode!r}")
    _check(self.v_range[0] < self.v_range[1], f"{key}.v_range", "needs min < max")
    _check(0.01 <= self.period <= 2.0, f"{key}.period", f"must be in [0.01, 2] s, got {self.period}")


@dataclasses.dataclass(frozen=True)
class ObservationConfig:
  parts: tuple[str, ...] = ("v", "flippers", "arm", "pitch", "vertical_beams")
  vertical_beams: int = 60  # N_v
  horizontal_beams: int = 12  # N_h
  band_px: int = 10  # px, width of the central band a beam averages over
  rays_per_band: tuple[int, int] = (2, 2)  # rays cast per band (along, across)
  depth_range: tuple[float, float] = (0.20, 1.50)  # m, hits outside are 0
  noise: float = 0.0  # fraction of rays hidden (the reference: 0.1 of the image in patches)

  PARTS = ("v", "w", "flippers", "flippers_paired", "arm", "pitch", "roll", "heading",
           "goal_distance", "angular_velocity", "vertical_beams", "horizontal_beams")

  def validate(self, key: str) -> None:
    for p in self.parts:
      _check(p in self.PARTS, f"{key}.parts", f"unknown part {p!r}; known: {self.PARTS}")
    _check(len(set(self.parts)) == len(self.parts), f"{key}.parts", "has duplicates")
    _check(1 <= self.vertical_beams <= 480, f"{key}.vertical_beams", "must be in [1, 480]")
    _check(1 <= self.horizontal_beams <= 640, f"{key}.horizontal_beams", "must be in [1, 640]")
    _check(1 <= self.band_px <= 480, f"{key}.band_px", "must be in [1, 480]")
    _check(min(self.rays_per_band) >= 1, f"{key}.rays_per_band", "must be >= 1")
    _check(0 <= self.depth_range[0] < self.depth_range[1], f"{key}.depth_range", "needs 0 <= min < max")
    _check(0.0 <= self.noise < 1.0, f"{key}.noise", "must be in [0, 1)")


@dataclasses.dataclass(frozen=True)
class CurriculumConfig:
  window: int = 20  # N_e finished episodes
  rule: str = "progress"  # "progress" (original code) | "return" (paper)

  def validate(self, key: str) -> None:
    _check(self.rule in ("progress", "return"), f"{key}.rule", "must be 'progress' or 'return'")
    _check(self.window >= 1, f"{key}.window", "must be >= 1")


@dataclasses.dataclass(frozen=True)
class SceneConfig:
  kind: str = "stairs"  # stairs | nav
  direction: str = "up"  # stairs: up | down
  sampler: str = "incremental"  # uniform | incremental
  variant: str = "difficulty"  # incremental: difficulty | paper_literal | original_code
  tread: tuple[float, float] = (0.35, 0.52)  # m, l
  riser: tuple[float, float] = (0.12, 0.22)  # m, h
  steps: tuple[int, int] = (1, 7)  # n
  nav_kinds: tuple[str, ...] = ("hallway", "zigzag")
  random_spawn: bool = False
  random_goal: bool = False
  curriculum: CurriculumConfig = CurriculumConfig()

  def validate(self, key: str) -> None:
    _check(self.kind in ("stairs", "nav"), f"{key}.kind", "must be 'stairs' or 'nav'")
    _check(self.direction in ("up", "down"), f"{key}.direction", "must be 'up' or 'down'")
    _check(self.sampler in ("uniform", "incremental"), f"{key}.sampler", "must be 'uniform' or 'incremental'")
    from scenes.samplers import VARIANTS  # noqa: PLC0415
    _check(self.variant in VARIANTS, f"{key}.variant", f"must be one of {VARIANTS}, got {self.variant!r}")
    _check(0.1 <= self.tread[0] <= self.tread[1] <= 1.0, f"{key}.tread", "needs 0.1 <= min <= max <= 1.0 m")
    _check(0.01 <= self.riser[0] <= self.riser[1] <= 0.4, f"{key}.riser", "needs 0.01 <= min <= max <= 0.4 m")
    _check(1 <= self.steps[0] <= self.steps[1] <= 7, f"{key}.steps", "needs 1 <= min <= max <= 7")
    self.curriculum.validate(f"{key}.curriculum")


@dataclasses.dataclass(frozen=True)
class RewardConfig:
  kind: str = "cog"  # free | cog | angular
  progress_scale: float = 1.0
  cog_scale: float = 0.05  # per-step COG deviation penalty weight (1/m)
  angular_scale: float = 0.05  # per-step |pitch rate| penalty weight (s/rad)
  tipover_penalty: float = 1.0
  normalize_penalties: bool = False  # the original's K = 1 / mean penalty sum of the first episodes
  normalize_episodes: int = 30
  safety_window: int = 5  # samples averaged by the penalty

  def validate(self, key: str) -> None:
    _check(self.kind in ("free", "cog", "angular"), f"{key}.kind", "must be 'free', 'cog' or 'angular'")
    for name in ("progress_scale", "cog_scale", "angular_scale", "tipover_penalty"):
      _check(getattr(self, name) >= 0, f"{key}.{name}", "must be >= 0")
    _check(self.normalize_episodes >= 1, f"{key}.normalize_episodes", "must be >= 1")
    _check(self.safety_window >= 1, f"{key}.safety_window", "must be >= 1")


@dataclasses.dataclass(frozen=True)
class EpisodeConfig:
  max_steps: int = 50  # control steps
  goal_tolerance: float = 0.3  # m, subtracted from the goal distance (reference)
  away_factor: float = 1.2  # terminate when dist > away_factor * d0

  def validate(self, key: str) -> None:
    _check(1 <= self.max_steps <= 100_000, f"{key}.max_steps", "must be in [1, 100000]")
    _check(self.goal_tolerance >= 0, f"{key}.goal_tolerance", "must be >= 0")
    _check(self.away_factor > 1.0, f"{key}.away_factor", "must be > 1")


@dataclasses.dataclass(frozen=True)
class PhysicsSection:
  timestep: float = 0.01  # s
  solver_iterations: int = 4
  ls_iterations: int = 6

  def validate(self, key: str) -> None:
    _check(0.0005 <= self.timestep <= 0.02, f"{key}.timestep", "must be in [0.0005, 0.02] s")
    _check(self.solver_iterations >= 1, f"{key}.solver_iterations", "must be >= 1")
    _check(self.ls_iterations >= 1, f"{key}.ls_iterations", "must be >= 1")


@dataclasses.dataclass(frozen=True)
class TaskConfig:
  task: str = "unnamed"
  robot: str = "1"
  control: ControlConfig = ControlConfig()
  observation: ObservationConfig = ObservationConfig()
  scene: SceneConfig = SceneConfig()
  reward: RewardConfig = RewardConfig()
  episode: EpisodeConfig = EpisodeConfig()
  physics: PhysicsSection = PhysicsSection()

  def validate(self, key: str = "") -> None:
    _check(str(self.robot) in ("1", "2", "jaguar", "absolem"), "robot", "must be 1 or 2")
    for f in dataclasses.fields(self):
      v = getattr(self, f.name)
      if dataclasses.is_dataclass(v):
        v.validate(f.name)
    if self.scene.kind == "nav":
      from mjx_tracks.control import CONTROL_MODES  # noqa: PLC0415
      _check("w" in CONTROL_MODES[self.control.mode], "control.mode",
             "navigation needs a mode with angular velocity w")
    steps = self.control.period / self.physics.timestep
    _check(abs(steps - round(steps)) < 1e-6, "control.period", "must be a multiple of physics.timestep")

  def to_dict(self) -> dict:
    return _to_plain(dataclasses.asdict(self))


def _to_plain(x):
  if isinstance(x, dict):
    return {k: _to_plain(v) for k, v in x.items()}
  if isinstance(x, (tuple, list)):
    return [_to_plain(v) for v in x]
  return x


def _convert(value: Any, tp: Any, key: str) -> Any:
  """Checks value against the annotation tp and converts lists to tuples."""
  origin = typing.get_origin(tp)
  if dataclasses.is_dataclass(tp):
    _check(isinstance(value, dict), key, f"must be a mapping, got {type(value).__name__}")
    return _build(tp, value, key)
  if origin is tuple:
    args = typing.get_args(tp)
    _check(isinstance(value, (list, tuple)), key, f"must be a list, got {value!r}")
    if len(args) == 2 and args[1] is Ellipsis:
      return tuple(_convert(v, args[0], f"{key}[{i}]") for i, v in enumerate(value))
    _check(len(value) == len(args), key, f"must have {len(args)} entries, got {len(value)}")
    return tuple(_convert(v, a, f"{key}[{i}]") for i, (v, a) in enumerate(zip(value, args)))
  if tp is float:
    _check(isinstance(value, (int, float)) and not isinstance(value, bool), key, f"must be a number, got {value!r}")
    return float(value)
  if tp is int:
    _check(isinstance(value, int) and not isinstance(value, bool), key, f"must be an integer, got {value!r}")
    return value
  if tp is bool:
    _check(isinstance(value, bool), key, f"must be true or false, got {value!r}")
    return value
  if tp is str:
    _check(isinstance(value, (str, int)) and not isinstance(value, bool), key, f"must be a string, got {value!r}")
    return str(value)
  raise ConfigError(f"{key}: unsupported type {tp}")


def _build(cls, raw: dict, key: str):
  hints = typing.get_type_hints(cls)
  names = {f.name for f in dataclasses.fields(cls)}
  for k in raw:
    _check(k in names, f"{key}.{k}".lstrip("."), f"unknown key; known: {sorted(names)}")
  kwargs = {k: _convert(v, hints[k], f"{key}.{k}".lstrip(".")) for k, v in raw.items()}
  return cls(**kwargs)


def _merge(base: dict, over: dict, key: str = "") -> dict:
  out = dict(base)
  for k, v in over.items():
    if isinstance(v, dict) and isinstance(base.get(k), dict):
      out[k] = _merge(base[k], v, f"{key}.{k}")
    else:
      out[k] = v
  return out


def _apply_override(raw: dict, item: str) -> dict:
  key, sep, value = item.partition("=")
  if not sep or not key:
    raise ConfigError(f"override {item!r}: expected KEY=VALUE, e.g. reward.cog_scale=0.5")
  patch: dict = {}
  node = patch
  parts = key.split(".")
  for p in parts[:-1]:
    node[p] = {}
    node = node[p]
  node[parts[-1]] = yaml.safe_load(value)
  return _merge(raw, patch)


def available_tasks() -> list[str]:
  """Task names: every configs/*.yaml except defaults.yaml."""
  return sorted(p.stem for p in CONFIG_DIR.glob("*.yaml") if p.stem != "defaults")


def from_dict(raw: dict) -> TaskConfig:
  """Builds and validates a TaskConfig from a (merged) plain mapping."""
  cfg = _build(TaskConfig, raw, "")
  cfg.validate()
  return cfg


def load_config(task: str, overrides: typing.Sequence[str] = ()) -> TaskConfig:
  """configs/defaults.yaml <- configs/<task>.yaml <- overrides, validated."""
  path = CONFIG_DIR / f"{task}.yaml"
  if not path.exists():
    raise ConfigError(f"unknown task {task!r}; available: {', '.join(available_tasks())}")
  raw: dict = {}
  for p in (CONFIG_DIR / "defaults.yaml", path):
    if p.exists():
      loaded = yaml.safe_load(p.read_text()) or {}
      if not isinstance(loaded, dict):
        raise ConfigError(f"{p.name}: top level must be a mapping")
      raw = _merge(raw, loaded)
  for item in overrides:
    raw = _apply_override(raw, item)
  return from_dict(raw)

"""Typed task configuration: configs/defaults.yaml <- configs/TASK.yaml <- dotted overrides.

Every section is a frozen dataclass with no defaults of its own: configs/defaults.yaml holds the
default of every key (with its unit and meaning). Loading checks that each key exists, each value's
type and each range, and fails with a message that names the dotted key.
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import itertools
import math
import re
import reprlib
import typing
from typing import Any

import yaml

from mjx_tracks.bounds import bound, violation
from mjx_tracks.envs.randomization import RandomizationConfig
from mjx_tracks.envs.task_files import DEFAULTS, available_tasks, config_dir  # noqa: F401  (re-exported)
from mjx_tracks.limits import MAX_NAME_CHARS, MAX_OVERRIDE_CHARS, MAX_YAML_CHARS, MAX_YAML_NODES
from mjx_tracks.sim.physics import PhysicsConfig
from scenes.navigation import (MAX_FLOOR_OBSTACLES, NAV_CLEARANCE_LIMITS, NAV_FLOOR_PASSAGE_LIMITS, NAV_GAP_LIMITS,
                               NAV_LENGTH_LIMITS)
from scenes.terrain_kinds import TERRAIN_PARAMS


class ConfigError(ValueError):
  """A configuration key, type or value is wrong; the message names it, and `key` holds it where known."""

  def __init__(self, message: str, key: str | None = None):
    super().__init__(message)
    self.key = key


def require(cond: bool, key: str, msg) -> None:
  """Raises ConfigError("KEY: MSG") unless cond; msg may be a callable, called only then."""
  if not cond:
    raise ConfigError(f"{key}: {msg() if callable(msg) else msg}", key)


_SHOW = reprlib.Repr()
_SHOW.maxstring, _SHOW.maxother, _SHOW.maxlist, _SHOW.maxdict, _SHOW.maxlevel = 60, 60, 6, 6, 3


def show(value) -> str:
  """A short repr of user input for a message: bounded in length and in the work it takes."""
  return _SHOW.repr(value)


PLAIN_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]*")  # names that are folder and file names too


def require_plain_name(name, key: str) -> None:
  """ConfigError unless `name` is a plain name (letters, digits, _ . -; not starting with _ . -)
  of at most MAX_NAME_CHARS characters."""
  ok = isinstance(name, str) and len(name) <= MAX_NAME_CHARS and PLAIN_NAME.fullmatch(name) is not None
  require(ok, key, lambda: f"{show(name)} is not a plain name (letters, digits, _ . -; at most "
                           f"{MAX_NAME_CHARS} characters)")


def _expanded_nodes(node, memo: dict) -> int:
  """How many nodes a YAML node graph has once its aliases are expanded (ValueError for a cycle)."""
  if id(node) in memo:
    if memo[id(node)] is None:
      raise ValueError("an alias refers to a node that contains it")
    return memo[id(node)]
  memo[id(node)] = None  # in progress
  children = node.value if isinstance(node, yaml.SequenceNode) else \
      [x for pair in node.value for x in pair] if isinstance(node, yaml.MappingNode) else []
  memo[id(node)] = 1 + sum(_expanded_nodes(c, memo) for c in children)
  return memo[id(node)]


SAFE_LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)  # libyaml's, where PyYAML has it: ~10x faster
NESTED_TOO_DEEPLY = "YAML nested too deeply"  # the one message, whichever layer refuses the depth


def load_yaml(text: str, source: str, key: str | None = None):
  """YAML text (of `source`, named in messages; `key`: the ConfigError's key) read safely: no tags,
  at most MAX_YAML_CHARS characters and MAX_YAML_NODES nodes with aliases expanded (an alias
  bomb), no recursive aliases; ConfigError in one line otherwise."""
  if len(text) > MAX_YAML_CHARS:
    raise ConfigError(f"{source}: over {MAX_YAML_CHARS:,} characters of YAML", key)
  loader = None
  try:
    loader = SAFE_LOADER(text)
    node = loader.get_single_node()
    if node is None:
      return None
    if _expanded_nodes(node, {}) > MAX_YAML_NODES:
      raise ConfigError(f"{source}: over {MAX_YAML_NODES:,} YAML nodes once its aliases (*name) are expanded", key)
    return loader.construct_document(node)
  except ConfigError:
    raise
  except yaml.YAMLError as e:
    why = str(getattr(e, "problem", None) or e).splitlines()[0]
    if "nesting depth" in why:  # PyYAML >= 6.0.4 limits the depth itself (older ones: RecursionError below)
      raise ConfigError(f"{source}: {NESTED_TOO_DEEPLY}", key) from None
    where = f" (line {e.problem_mark.line + 1}, column {e.problem_mark.column + 1})" \
        if getattr(e, "problem_mark", None) else ""
    raise ConfigError(f"{source}: not valid YAML{where}: {why}", key) from None
  except ValueError as e:
    raise ConfigError(f"{source}: {e}", key) from None
  except RecursionError:
    raise ConfigError(f"{source}: {NESTED_TOO_DEEPLY}", key) from None
  finally:
    if loader is not None:
      loader.dispose()


@dataclasses.dataclass(frozen=True)
class SafetyFilterConfig:
  """control.safety_filter: mjx_tracks.envs.safety_filter."""
  enabled: bool
  rays: int = dataclasses.field(metadata=bound(8, 720))  # rays of its horizontal scan ring
  horizon: float = dataclasses.field(metadata=bound(0.05, 5.0))  # s, how long each command is predicted held
  samples: int = dataclasses.field(metadata=bound(1, 50))  # predicted poses, evenly in (0, horizon]
  margin: float = dataclasses.field(metadata=bound(0.0, 1.0))  # m, the least clearance a kept command keeps
  response: float = dataclasses.field(metadata=bound(0.0, 2.0))  # s, the predicted motion's approach from the measured one (0: none)
  reverse: float = dataclasses.field(metadata=bound(0.0, 2.0))  # m/s, backing speed of a held robot (0: it stands)


@dataclasses.dataclass(frozen=True)
class ControlConfig:
  mode: str  # mjx_tracks.sim.control.CONTROL_MODES
  increments: bool  # the original's +-pi/10 increments, else absolute targets
  v_range: tuple[float, float]  # m/s
  period: float = dataclasses.field(metadata=bound(0.01, 2.0))  # s between actions
  dof_curriculum: tuple[tuple[str, float], ...]  # (joint action dimension, eps from which it acts)
  start_pose: tuple[tuple[str, float], ...]  # (joint group, rad): where those joints start; the others at 0
  safety_filter: SafetyFilterConfig  # a layer under the policy that slows a command heading into a wall

  def validate(self, key: str) -> None:
    from mjx_tracks.sim.control import CONTROL_MODES, unlock_values  # noqa: PLC0415
    require(self.mode in CONTROL_MODES, f"{key}.mode", f"must be one of {sorted(CONTROL_MODES)}, got {self.mode!r}")
    require(self.v_range[0] < self.v_range[1], f"{key}.v_range", "needs min < max")
    try:
      unlock_values(CONTROL_MODES[self.mode], self.dof_curriculum)
    except ValueError as e:
      require(False, f"{key}.dof_curriculum", str(e).partition(": ")[2])
    from mjx_tracks.robots.spec import JOINT_GROUPS  # noqa: PLC0415
    for group, angle in self.start_pose:
      require(group in JOINT_GROUPS, f"{key}.start_pose", f"{group!r} is not a joint group; known: {sorted(JOINT_GROUPS)}")
      require(abs(angle) <= math.pi, f"{key}.start_pose", f"{group}: {angle} rad is not an angle in [-pi, pi]")


@dataclasses.dataclass(frozen=True)
class ObservationConfig:
  parts: tuple[str, ...]  # names in mjx_tracks.envs.observations.PARTS
  vertical_beams: int = dataclasses.field(metadata=bound(1, 480))  # N_v
  horizontal_beams: int = dataclasses.field(metadata=bound(1, 640))  # N_h
  band_px: int = dataclasses.field(metadata=bound(1, 480))  # px, width of the central band a beam averages over
  rays_per_band: tuple[int, int]  # rays cast per band (along, across)
  depth_range: tuple[float, float]  # m, hits outside are 0
  noise: float = dataclasses.field(metadata=bound(0.0, 1.0, hi_open=True))  # fraction of rays hidden
  scan_rays: int = dataclasses.field(metadata=bound(1, 360))  # N_s, the laser scan's rays (part "scan")
  scan_range: float = dataclasses.field(metadata=bound(0.5, 30.0))  # m, a scan ray's reading where it hits nothing
  scan_pitches: tuple[float, ...]  # rad, the scan's rings, each pitched down from the chassis plane (0: horizontal)
  history: int = dataclasses.field(metadata=bound(1, 16))  # control steps stacked (mjx_tracks.envs.observations.stack)

  def validate(self, key: str) -> None:
    from mjx_tracks.envs.observations import PARTS  # noqa: PLC0415
    for p in self.parts:
      require(p in PARTS, f"{key}.parts", f"unknown part {p!r}; known: {sorted(PARTS)}")
    require(len(set(self.parts)) == len(self.parts), f"{key}.parts", "has duplicates")
    require(min(self.rays_per_band) >= 1, f"{key}.rays_per_band", "must be >= 1")
    require(0 <= self.depth_range[0] < self.depth_range[1], f"{key}.depth_range", "needs 0 <= min < max")
    require(1 <= len(self.scan_pitches) <= 8 and all(0.0 <= p < 1.5 for p in self.scan_pitches),
            f"{key}.scan_pitches", f"needs 1-8 rings pitched down 0 <= p < 1.5 rad, got {list(self.scan_pitches)}")


@dataclasses.dataclass(frozen=True)
class CurriculumConfig:
  window: int = dataclasses.field(metadata=bound(1))  # N_e finished episodes
  rule: str  # scenes.curriculum.RULES

  def validate(self, key: str) -> None:
    from scenes.curriculum import RULES  # noqa: PLC0415
    require(self.rule in RULES, f"{key}.rule", f"must be one of {RULES}, got {self.rule!r}")


def _terrain_ranges_class():
  """scene.terrain: a section per terrain kind (scenes.terrain_kinds), a [min, max] per parameter."""
  kinds = []
  for kind, p in TERRAIN_PARAMS.items():
    fields = [(n, tuple[int, int] if i else tuple[float, float]) for n, i in zip(p.names, p.integer)]
    kinds.append((kind, dataclasses.make_dataclass(f"{kind.title().replace('_', '')}Ranges", fields, frozen=True)))
  return dataclasses.make_dataclass("TerrainRanges", kinds, frozen=True)


TerrainRanges = _terrain_ranges_class()


def _validate_terrain_ranges(ranges, key: str) -> None:
  """Every terrain kind's ranges (any task's) against what its generator supports."""
  for kind, p in TERRAIN_PARAMS.items():
    r = getattr(ranges, kind)
    for name, (lo, hi) in zip(p.names, p.limits):
      v = getattr(r, name)
      require(lo <= v[0] <= v[1] <= hi, f"{key}.terrain.{kind}.{name}", f"needs {lo} <= min <= max <= {hi}, got {list(v)}")
    for corner in itertools.product(*(getattr(r, name) for name in p.names)):
      problem = p.check(corner)
      require(not problem, f"{key}.terrain.{kind}", f"at {list(corner)}: {problem}")


_RENAMED_VARIANTS = {"paper": "paper_literal", "original": "original_code"}


@dataclasses.dataclass(frozen=True)
class SceneConfig:
  kind: str  # scenes.kinds.SCENE_KINDS
  direction: str  # stairs: up | down
  sampler: str  # scenes.samplers.SAMPLERS
  variant: str  # scenes.samplers.VARIANTS
  tread: tuple[float, float]  # m, l
  riser: tuple[float, float]  # m, h
  steps: tuple[int, int]  # n
  nav_kinds: tuple[str, ...]
  nav_floor_obstacles: int = dataclasses.field(metadata=bound(0, MAX_FLOOR_OBSTACLES))  # nav: low boxes in the obstacle area
  nav_floor_height: tuple[float, float]  # m, nav: their height ~ U(min, max)
  nav_gap: tuple[float, float]  # m, nav: the gap C between the wall obstacles ~ U(min, max) (hard: narrow)
  nav_clearance: float = dataclasses.field(metadata=bound(*NAV_CLEARANCE_LIMITS))  # m, nav: the free-space path's distance from walls
  nav_floor_passage: float = dataclasses.field(metadata=bound(*NAV_FLOOR_PASSAGE_LIMITS))  # m, nav: disc radius with a way round the floor obstacles (0: none asked)
  nav_length: float = dataclasses.field(metadata=bound(*NAV_LENGTH_LIMITS))  # m, nav: the area's length along x
  terrains: tuple[str, ...]  # terrain: the kinds drawn per episode (scenes.terrain)
  terrain: TerrainRanges  # every terrain kind's parameter ranges
  random_spawn: bool
  random_goal: bool
  start_jitter: tuple[float, float, float]  # ~ U(-a, a) each: start x and y (m), yaw (rad), joint angles (rad)
  curriculum: CurriculumConfig

  @property
  def has_hardest(self) -> bool:
    """Whether its scenes have a hardest configuration (every parameter at its hard end)."""
    from scenes.kinds import scene_kind  # noqa: PLC0415
    return scene_kind(self.kind).has_hardest(self)

  @property
  def probe_scene(self) -> str | None:
    """The scene of in-training probes and `--early-stop success` (SceneKind.probe_scene); None: none."""
    from scenes.kinds import scene_kind  # noqa: PLC0415
    return scene_kind(self.kind).probe_scene(self)

  def validate(self, key: str) -> None:
    """The keys every kind has; the kind's own checks run in TaskConfig.validate (they may need
    other sections)."""
    from scenes.kinds import SCENE_KINDS  # noqa: PLC0415
    from scenes.samplers import SAMPLERS, VARIANTS  # noqa: PLC0415
    from scenes.terrain_kinds import STAIRS  # noqa: PLC0415
    require(self.kind in SCENE_KINDS, f"{key}.kind", f"must be one of {list(SCENE_KINDS)}, got {self.kind!r}")
    _validate_terrain_ranges(self.terrain, key)
    lo, hi = self.nav_floor_height
    require(0.01 <= lo <= hi <= 0.5, f"{key}.nav_floor_height", f"needs 0.01 <= min <= max <= 0.5, got {[lo, hi]}")
    validate_nav_gap(self.nav_gap, f"{key}.nav_gap")
    require(self.direction in ("up", "down"), f"{key}.direction", "must be 'up' or 'down'")
    require(self.sampler in SAMPLERS, f"{key}.sampler", f"must be one of {SAMPLERS}, got {self.sampler!r}")
    hint = f" ({self.variant!r} is now {_RENAMED_VARIANTS[self.variant]!r})" if self.variant in _RENAMED_VARIANTS else ""
    require(self.variant in VARIANTS, f"{key}.variant", f"must be one of {VARIANTS}, got {self.variant!r}{hint}")
    for name, (lo, hi) in zip(STAIRS.names, STAIRS.limits):
      r = getattr(self, name)
      require(lo <= r[0] <= r[1] <= hi, f"{key}.{name}", f"needs {lo} <= min <= max <= {hi}, got {list(r)}")
    self.curriculum.validate(f"{key}.curriculum")
    validate_jitter(self.start_jitter, f"{key}.start_jitter")


# how the safety penalty is spread over an episode (mjx_tracks.envs.rewards.Monitor): the paper's moving
# window of samples per step, or the change of the episode's running mean (its sum: the mean)
SAFETY_FORMS = ("window", "episode_mean")
def validate_nav_gap(gap: tuple[float, float], key: str) -> None:
  """A navigation gap range C ~ U(min, max) (m) within NAV_GAP_LIMITS."""
  lo, hi = gap
  require(NAV_GAP_LIMITS[0] <= lo <= hi <= NAV_GAP_LIMITS[1], key,
          f"needs {NAV_GAP_LIMITS[0]} <= min <= max <= {NAV_GAP_LIMITS[1]}, got {[lo, hi]}")


PROGRESS_FORMS = ("closest", "potential")  # mjx_tracks.envs.rewards: the paper's closest-so-far rule | potential-based
DISTANCES = ("euclidean", "geodesic")  # what the goal distance measures (scenes.kinds: SceneKind.distances)
JITTER_LIMITS = (0.5, 3.1416, 1.0)  # m, rad, rad: the most a start jitter / trial variation may vary


def validate_jitter(a: tuple[float, float, float], key: str) -> None:
  """A (position m, yaw rad, joints rad) half-width triple, each from 0 to its JITTER_LIMITS."""
  require(len(a) == 3 and all(0.0 <= v <= hi for v, hi in zip(a, JITTER_LIMITS)), key,
          lambda: f"[position m, yaw rad, joints rad], each from 0 to {list(JITTER_LIMITS)}, got {show(a)}")


# each reward kind -> the safety signal (a per-step metric) its penalty reads; a scene kind must measure it
REWARD_SIGNALS = {"free": None, "cog": "cog_deviation", "angular": "pitch_rate"}


@dataclasses.dataclass(frozen=True)
class RewardConfig:
  kind: str  # REWARD_SIGNALS
  progress_scale: float = dataclasses.field(metadata=bound(0.0))
  cog_scale: float = dataclasses.field(metadata=bound(0.0))  # per-step COG deviation penalty weight (1/m)
  angular_scale: float = dataclasses.field(metadata=bound(0.0))  # per-step |pitch rate| penalty weight (s/rad)
  tipover_penalty: float = dataclasses.field(metadata=bound(0.0))
  goal_bonus: float = dataclasses.field(metadata=bound(0.0))  # reward on reaching the goal
  normalize_penalties: bool  # the original's K = 1 / mean penalty sum of the first episodes
  normalize_episodes: int = dataclasses.field(metadata=bound(1))
  safety_window: int = dataclasses.field(metadata=bound(1))  # samples averaged by the penalty
  safety_form: str  # SAFETY_FORMS
  progress_form: str  # PROGRESS_FORMS
  collision_penalty: float = dataclasses.field(metadata=bound(0.0))  # per control step with a collision
  clearance_penalty: float = dataclasses.field(metadata=bound(0.0))  # per control step at clearance 0 (nav)
  clearance_margin: float = dataclasses.field(metadata=bound(0.01, 2.0))  # m, the clearance below which it pays
  riding_penalty: float = dataclasses.field(metadata=bound(0.0))  # per control step with a belt on a floor obstacle (nav)

  def validate(self, key: str) -> None:
    require(self.kind in REWARD_SIGNALS, f"{key}.kind", lambda: f"must be one of {list(REWARD_SIGNALS)}, got {show(self.kind)}")
    require(self.safety_form in SAFETY_FORMS, f"{key}.safety_form",
            lambda: f"must be one of {list(SAFETY_FORMS)}, got {show(self.safety_form)}")
    require(self.progress_form in PROGRESS_FORMS, f"{key}.progress_form",
            lambda: f"must be one of {list(PROGRESS_FORMS)}, got {show(self.progress_form)}")


@dataclasses.dataclass(frozen=True)
class EpisodeConfig:
  max_steps: int = dataclasses.field(metadata=bound(1, 100_000))  # control steps
  goal_tolerance: float = dataclasses.field(metadata=bound(0.0))  # m, subtracted from the goal distance (reference)
  away_factor: float = dataclasses.field(metadata=bound(1.0, lo_open=True))  # terminate when dist > away_factor * d0
  distance: str  # DISTANCES: what dist and d0 measure
  end_on_collision: bool  # a collision (scenes.kinds: SceneKind.collision_geoms) ends the episode

  def validate(self, key: str) -> None:
    require(self.distance in DISTANCES, f"{key}.distance",
            lambda: f"must be one of {list(DISTANCES)}, got {show(self.distance)}")


@dataclasses.dataclass(frozen=True)
class HeldOutScene:
  """A fixed staircase every finished study run is evaluated on (not drawn by the training sampler)."""
  name: str
  tread: float  # m, l
  riser: float  # m, h
  steps: int  # n

  def validate(self, key: str) -> None:
    from scenes.terrain_kinds import STAIRS  # noqa: PLC0415
    require_plain_name(self.name, f"{key}.name")
    for name, (lo, hi) in zip(STAIRS.names, STAIRS.limits):
      require(lo <= getattr(self, name) <= hi, f"{key}.{name}", f"must be in [{lo}, {hi}], got {getattr(self, name)}")


@dataclasses.dataclass(frozen=True)
class HeldOutTerrain:
  """A fixed terrain of one kind every finished study run of a terrain task drawing that kind is
  evaluated on: its parameters in the kind's order (scenes.terrain_kinds)."""
  name: str
  kind: str
  values: tuple[float, ...]

  def validate(self, key: str) -> None:
    require_plain_name(self.name, f"{key}.name")
    require(self.kind in TERRAIN_PARAMS, f"{key}.kind", f"must be one of {list(TERRAIN_PARAMS)}, got {self.kind!r}")
    p = TERRAIN_PARAMS[self.kind]
    require(len(self.values) == len(p.names), f"{key}.values", f"{self.kind} takes {list(p.names)}, got {list(self.values)}")
    for name, v, (lo, hi) in zip(p.names, self.values, p.limits):
      require(lo <= v <= hi, f"{key}.values", f"{name} must be in [{lo}, {hi}], got {v}")
    problem = p.check(tuple(self.values))
    require(not problem, f"{key}.values", problem)


@dataclasses.dataclass(frozen=True)
class HeldOutNav:
  """Navigation areas every finished study run of a nav task is evaluated on, beyond its training
  ranges: the task's areas (or those of `areas`) with these gaps, floor obstacles and length."""
  name: str
  gap: tuple[float, float]  # m, C ~ U(min, max) (SceneConfig.nav_gap)
  floor_obstacles: int = dataclasses.field(metadata=bound(0, MAX_FLOOR_OBSTACLES))
  length: float = dataclasses.field(metadata=bound(*NAV_LENGTH_LIMITS))  # m, the area's length (SceneConfig.nav_length)
  areas: tuple[str, ...] = ()  # area kinds drawn, of the task's (SceneConfig.nav_kinds); (): the task's

  def validate(self, key: str) -> None:
    require_plain_name(self.name, f"{key}.name")
    validate_nav_gap(self.gap, f"{key}.gap")


@dataclasses.dataclass(frozen=True)
class RobustnessCase:
  """One case of the robustness suite: the nominal robot with these overrides (KEY=VALUE)."""
  name: str
  set: tuple[str, ...]

  def validate(self, key: str) -> None:
    """Each override names a randomization key (not enabled, grow) or observation.noise; their values
    are checked against the task's sections (TaskConfig.validate: check_case)."""
    require_plain_name(self.name, f"{key}.name")
    for item in self.set:
      require(isinstance(item, str) and item.startswith(PERTURBABLE) and item.partition("=")[0] not in
              ("randomization.enabled", "randomization.grow"), f"{key}.set",
              lambda: f"overrides of {' or '.join(PERTURBABLE)} keys (not enabled, grow), got {show(item)}")

  def check_case(self, randomization: RandomizationConfig, substeps: int, key: str) -> None:
    """Each override's value of its type and range, applied to the nominal robot of a task's
    randomization section whose control period lasts `substeps` (the case's fit to it is checked
    when it runs)."""
    from mjx_tracks.envs.randomization import nominal_section, resolve_period  # noqa: PLC0415
    raw = {"randomization": nominal_section(dataclasses.asdict(randomization)), "observation": {"noise": 0.0}}
    try:
      for item in self.set:
        raw = apply_override(raw, item)
      section = resolve_period(raw["randomization"], substeps)
      parse_mapping(RandomizationConfig, section, "randomization").validate("randomization")
      require(0.0 <= raw["observation"]["noise"] < 1.0, "observation.noise", "must be in [0, 1)")
    except ConfigError as e:
      raise ConfigError(f"{key}.set: {e}", e.key) from None


PERTURBABLE = ("randomization.", "observation.noise=")  # what a robustness case may change


@dataclasses.dataclass(frozen=True)
class EvaluationConfig:
  trial_variation: tuple[float, float, float]  # evaluation scenes' start jitter (SceneConfig.start_jitter)
  held_out: tuple[HeldOutScene, ...]  # stair tasks: fixed staircases of the evaluation suite
  held_out_terrain: tuple[HeldOutTerrain, ...]  # terrain tasks: fixed terrains of the kinds they draw
  held_out_nav: tuple[HeldOutNav, ...]  # nav tasks: areas with narrower gaps or denser floor obstacles
  robustness: tuple[RobustnessCase, ...]  # train.evaluate --robustness: the cases of the robustness suite

  def validate(self, key: str) -> None:
    validate_jitter(self.trial_variation, f"{key}.trial_variation")
    for field in ("held_out", "held_out_terrain", "held_out_nav", "robustness"):
      names = [h.name for h in getattr(self, field)]
      require(len(set(names)) == len(names), f"{key}.{field}", f"names repeat: {names}")
      for i, h in enumerate(getattr(self, field)):
        h.validate(f"{key}.{field}[{i}]")


@dataclasses.dataclass(frozen=True)
class TaskConfig:
  """A task: every section; the defaults of every key live in configs/defaults.yaml."""

  task: str
  robot: str
  control: ControlConfig
  observation: ObservationConfig
  scene: SceneConfig
  reward: RewardConfig
  episode: EpisodeConfig
  physics: PhysicsConfig
  evaluation: EvaluationConfig
  randomization: RandomizationConfig

  def validate(self, key: str = "") -> None:
    """Every section, then what needs several: the robot's joints, the scene kind's own checks
    (scenes.kinds), the reward's safety signal, the control period."""
    from mjx_tracks.robots import ROBOTS  # noqa: PLC0415
    from scenes.kinds import scene_kind  # noqa: PLC0415
    require(str(self.robot) in ROBOTS, "robot", f"must be one of {sorted(ROBOTS)}, got {self.robot!r}")
    for f in dataclasses.fields(self):
      v = getattr(self, f.name)
      if dataclasses.is_dataclass(v):
        try:
          v.validate(f.name)
        except ConfigError:
          raise
        except ValueError as e:
          raise ConfigError(str(e)) from e
    _validate_robot(self)
    kind = scene_kind(self.scene.kind)
    kind.validate(self)
    signal = REWARD_SIGNALS[self.reward.kind]
    require(signal is None or signal in kind.signals, "reward.kind",
            lambda: f"{self.reward.kind!r} penalizes {signal}, which {self.scene.kind} scenes do not measure "
                    f"(they measure {list(kind.signals)}); use one of "
                    f"{[k for k, s in REWARD_SIGNALS.items() if s is None or s in kind.signals]}")
    require(self.episode.distance in kind.distances, "episode.distance",
            lambda: f"{self.scene.kind} scenes measure {list(kind.distances)}, not {self.episode.distance!r}")
    require("collision" in kind.signals or not (self.episode.end_on_collision or self.reward.collision_penalty),
            "episode.end_on_collision" if self.episode.end_on_collision else "reward.collision_penalty",
            lambda: f"{self.scene.kind} scenes have nothing to collide with (collisions: nav scenes)")
    require("collision" in kind.signals or not self.control.safety_filter.enabled, "control.safety_filter.enabled",
            lambda: f"the safety filter reads walls from a horizontal scan, which {self.scene.kind} scenes do not have "
                    "(on stairs or terrain it would read the ground ahead as a wall); nav scenes only")
    require("collision" in kind.signals or not self.reward.riding_penalty, "reward.riding_penalty",
            lambda: f"{self.scene.kind} scenes have no floor obstacles to ride on (nav scenes)")
    require("clearance" in kind.signals or not self.reward.clearance_penalty, "reward.clearance_penalty",
            lambda: f"{self.scene.kind} scenes measure no clearance from walls (it is measured in nav scenes)")
    steps = self.control.period / self.physics.timestep
    require(abs(steps - round(steps)) < 1e-6, "control.period", "must be a multiple of physics.timestep")
    for i, case in enumerate(self.evaluation.robustness):
      case.check_case(self.randomization, round(steps), f"evaluation.robustness[{i}]")
    r = self.randomization  # its ranges act only where it is enabled
    require(not r.enabled or r.action_delay[1] <= round(steps), "randomization.action_delay",
            lambda: f"at most a control period, {round(steps)} substeps, got {list(r.action_delay)}")
    require(not r.enabled or r.period_jitter < round(steps), "randomization.period_jitter",
            lambda: f"less than a control period, {round(steps)} substeps, got {r.period_jitter}")

  def to_dict(self) -> dict:
    return _to_plain(dataclasses.asdict(self))


def _validate_robot(cfg: TaskConfig) -> None:
  """The control mode and observation against the robot's joints and speed."""
  from mjx_tracks.robots import get_robot  # noqa: PLC0415
  from mjx_tracks.sim.control import CONTROL_MODES  # noqa: PLC0415
  robot = get_robot(cfg.robot)
  arm_dims = [d for d in CONTROL_MODES[cfg.control.mode] if d.startswith("arm")]
  require(robot.has_arm or not arm_dims, "control.mode",
          lambda: f"{cfg.control.mode!r} drives the arm ({arm_dims}), but robot {cfg.robot} ({robot.name}) has none; "
                  f"use one of {sorted(m for m, d in CONTROL_MODES.items() if not any(x.startswith('arm') for x in d))}")
  require(robot.has_arm or "arm" not in cfg.observation.parts, "observation.parts",
          lambda: f"'arm' needs a robot with an arm; robot {cfg.robot} ({robot.name}) has none")
  lo, hi = cfg.control.v_range
  require(-robot.max_speed <= lo < hi <= robot.max_speed, "control.v_range",
          lambda: f"must lie inside +-{robot.max_speed} m/s for robot {cfg.robot}, got {[lo, hi]}")


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
    require(isinstance(value, dict), key, f"must be a mapping, got {type(value).__name__}")
    return _build(tp, value, key)
  if origin is tuple:
    args = typing.get_args(tp)
    require(isinstance(value, (list, tuple)), key, lambda: f"must be a list, got {show(value)}")
    if len(args) == 2 and args[1] is Ellipsis:
      return tuple(_convert(v, args[0], f"{key}[{i}]") for i, v in enumerate(value))
    require(len(value) == len(args), key, f"must have {len(args)} entries, got {len(value)}")
    return tuple(_convert(v, a, f"{key}[{i}]") for i, (v, a) in enumerate(zip(value, args)))
  if tp is float:
    require(isinstance(value, (int, float)) and not isinstance(value, bool), key,
            lambda: f"must be a number, got {show(value)}")
    return float(value)
  if tp is int:
    require(isinstance(value, int) and not isinstance(value, bool), key, lambda: f"must be an integer, got {show(value)}")
    return value
  if tp is bool:
    require(isinstance(value, bool), key, lambda: f"must be true or false, got {show(value)}")
    return value
  if tp is str:
    require(isinstance(value, (str, int)) and not isinstance(value, bool), key,
            lambda: f"must be a string, got {show(value)}")
    return str(value)
  raise ConfigError(f"{key}: unsupported type {tp}")


def _build(cls, raw: dict, key: str):
  hints = typing.get_type_hints(cls)
  names = [f.name for f in dataclasses.fields(cls)]
  for k in raw:
    name = k if isinstance(k, str) and len(k) <= MAX_NAME_CHARS else show(k)
    require(k in names, f"{key}.{name}".lstrip("."), lambda: f"unknown key; known: {sorted(names)}")
  missing = [n for n in names if n not in raw]
  require(not missing, key or "config", f"missing keys {missing}")
  built = cls(**{k: _convert(v, hints[k], f"{key}.{k}".lstrip(".")) for k, v in raw.items()})
  wrong = violation(built)  # the ranges declared on its fields (mjx_tracks.bounds)
  if wrong is not None:
    require(False, f"{key}.{wrong[0]}".lstrip("."), wrong[1])
  return built


def parse_mapping(cls, raw: dict, key: str = ""):
  """A config dataclass from a plain mapping, every key and type checked (ConfigError names the key)."""
  return _build(cls, raw, key)


def _merge(base: dict, over: dict, key: str = "") -> dict:
  out = dict(base)
  for k, v in over.items():
    if isinstance(v, dict) and isinstance(base.get(k), dict):
      out[k] = _merge(base[k], v, f"{key}.{k}")
    else:
      out[k] = v
  return out


def apply_override(raw: dict, item: str) -> dict:
  """raw with one dotted KEY=VALUE override (VALUE read as YAML) merged in."""
  if not isinstance(item, str) or len(item) > MAX_OVERRIDE_CHARS:
    raise ConfigError(f"override {show(item)}: a KEY=VALUE string of at most {MAX_OVERRIDE_CHARS} characters")
  key, sep, value = item.partition("=")
  if not sep or not key:
    raise ConfigError(f"override {show(item)}: expected KEY=VALUE, e.g. reward.cog_scale=0.5")
  patch: dict = {}
  node = patch
  parts = key.split(".")
  for p in parts[:-1]:
    node[p] = {}
    node = node[p]
  node[parts[-1]] = load_yaml(value, f"override {key}", key)
  return _merge(raw, patch)


def _read_yaml(name: str) -> dict:
  """configs/NAME.yaml as a mapping (a fresh copy; parsed once per version of the file)."""
  path = config_dir().joinpath(f"{name}.yaml")
  text = path.read_text()
  return copy.deepcopy(_parsed(name, text))


@functools.lru_cache(maxsize=256)
def _parsed(name: str, text: str) -> dict:
  loaded = load_yaml(text, f"{name}.yaml") or {}
  if not isinstance(loaded, dict):
    raise ConfigError(f"{name}.yaml: top level must be a mapping")
  return loaded


FROM_DEFAULTS = "from configs/defaults.yaml"  # an added key whose old runs never read it
# keys added since runs were first recorded -> the value that reproduces what those runs ran
ADDED_KEYS = {("physics", "contact_slots"): -1, ("physics", "box_pairs"): -1,  # before culling: every contact
              ("evaluation", "held_out"): [],  # before the evaluation suite: none
              ("control", "dof_curriculum"): [],  # before the DOF curriculum: every dimension acts
              ("control", "start_pose"): [],  # before start poses: every joint at 0
              ("control", "safety_filter"): FROM_DEFAULTS,  # before the safety filter: none (enabled: false)
              ("control", "safety_filter", "response"): 0.0,  # (after the line above) before it: the unicycle
              ("control", "safety_filter", "reverse"): 0.0,  # before it: a held robot stands
              ("scene", "terrains"): [],  # before terrain tasks: none
              ("scene", "nav_floor_obstacles"): 0,  # before floor obstacles: none
              ("scene", "nav_floor_height"): FROM_DEFAULTS,
              ("scene", "terrain"): FROM_DEFAULTS,
              ("scene", "terrain", "spiral_up"): FROM_DEFAULTS, ("scene", "terrain", "spiral_down"): FROM_DEFAULTS,
              ("scene", "start_jitter"): [0.0, 0.0, 0.0],  # before start jitter: the fixed spawn
              ("reward", "safety_form"): "window",  # before safety forms: the paper's window
              ("reward", "goal_bonus"): 0.0,  # before the goal term: none
              ("evaluation", "trial_variation"): FROM_DEFAULTS,  # evaluation only: old runs are evaluated as today's
              ("evaluation", "held_out_terrain"): FROM_DEFAULTS,  # evaluation only: old runs get today's
              ("evaluation", "held_out_nav"): FROM_DEFAULTS,  # evaluation only: old runs get today's
              ("scene", "nav_gap"): [1.0, 2.0],  # before the gap setting: the original's U(1, 2) m
              ("scene", "nav_clearance"): 0.4,  # before the setting: robot 1's half-width
              ("scene", "nav_floor_passage"): 0.0,  # before the setting: floor obstacles drawn regardless
              ("scene", "nav_length"): 12.0,  # before the setting: every area 12 m long
              ("reward", "progress_form"): "closest",  # before potential shaping: the paper's closest distance
              ("reward", "collision_penalty"): 0.0,  # before collision safety: no penalty
              ("reward", "clearance_penalty"): 0.0,  # before the clearance term: none
              ("reward", "clearance_margin"): FROM_DEFAULTS,  # read only by that term
              ("reward", "riding_penalty"): 0.0,  # before the riding term: none
              ("episode", "distance"): "euclidean",  # before free-space distances: straight lines
              ("episode", "end_on_collision"): False,  # before collision safety: collisions go on
              ("randomization",): FROM_DEFAULTS,  # before sim-to-real randomization: off (enabled: false)
              ("evaluation", "robustness"): FROM_DEFAULTS,  # evaluation only: old runs get today's
              ("observation", "scan_rays"): FROM_DEFAULTS,  # before the laser scan: read only by its part,
              ("observation", "scan_range"): FROM_DEFAULTS,  #   which no older run observes
              ("observation", "scan_pitches"): [0.0],  # before scan rings: the horizontal scan alone
              ("observation", "history"): 1}  # before observation history: the current step alone


# keys added to the entries of a list -> the value each older entry had
ADDED_ENTRY_KEYS = {("evaluation", "held_out_nav", "length"): 12.0,  # before longer areas: 12 m, as trained
                    ("evaluation", "held_out_nav", "areas"): []}  # before the key: the task's area kinds


def _with_added_keys(raw: dict) -> dict:
  """A recorded config (run.json) from before a key existed, with that key's old behaviour."""
  raw = copy.deepcopy(raw)
  defaults = functools.cache(lambda: _read_yaml(DEFAULTS))  # read once, if a key needs it
  for path, value in ADDED_KEYS.items():
    node = raw
    for part in path[:-1]:
      node = node.setdefault(part, {}) if isinstance(node, dict) else None
    if isinstance(node, dict) and path[-1] not in node:
      node[path[-1]] = functools.reduce(dict.get, path, defaults()) if value == FROM_DEFAULTS else value
  for (*path, key), value in ADDED_ENTRY_KEYS.items():
    entries = functools.reduce(lambda n, part: n.get(part) if isinstance(n, dict) else None, path, raw)
    for entry in entries if isinstance(entries, list) else ():
      if isinstance(entry, dict):
        entry.setdefault(key, value)
  return raw


def _with_period_resolved(raw: dict) -> dict:
  """randomization.action_delay's `period` (randomization.PERIOD) as the task's control period in
  substeps; left as written where the period or timestep is not a number (the build names the key)."""
  from mjx_tracks.envs.randomization import resolve_period  # noqa: PLC0415
  section = lambda name: raw.get(name) if isinstance(raw.get(name), dict) else {}
  period, dt = section("control").get("period"), section("physics").get("timestep")
  if not all(isinstance(x, (int, float)) and not isinstance(x, bool) and x > 0 for x in (period, dt)):
    return raw
  return {**raw, "randomization": resolve_period(raw.get("randomization"), round(period / dt))}


def from_dict(raw: dict) -> TaskConfig:
  """Builds and validates a TaskConfig from a complete plain mapping (e.g. a run's run.json)."""
  cfg = _build(TaskConfig, _with_period_resolved(_with_added_keys(raw)), "")
  cfg.validate()
  return cfg


def default_config(overrides: typing.Sequence[str] = ()) -> TaskConfig:
  """configs/defaults.yaml alone (plus overrides): the defaults of every key."""
  raw = {"task": DEFAULTS, **_read_yaml(DEFAULTS)}
  for item in overrides:
    raw = apply_override(raw, item)
  return from_dict(raw)


MAX_EXTENDS = 4  # how deep task files may extend one another


def _task_yaml(task: str, seen: tuple[str, ...] = ()) -> dict:
  """configs/<task>.yaml merged over the task it `extends` (a task's variant states only what differs)."""
  if task not in available_tasks():
    key = "task" if not seen else f"{seen[-1]}.yaml: extends"
    raise ConfigError(f"unknown task {task!r}; available: {', '.join(available_tasks())}", key)
  raw = _read_yaml(task)
  base = raw.pop("extends", None)
  if base is None:
    return raw
  require(isinstance(base, str) and base not in (*seen, task) and len(seen) < MAX_EXTENDS, f"{task}.yaml: extends",
          lambda: f"must name another task, without cycles, at most {MAX_EXTENDS} deep; got {show(base)}")
  inherited = _task_yaml(base, (*seen, task))
  inherited.pop("task", None)  # the variant is its own task
  return _merge(inherited, raw)


def load_config(task: str, overrides: typing.Sequence[str] = ()) -> TaskConfig:
  """configs/defaults.yaml <- configs/<task>.yaml (over the task it extends) <- overrides, validated."""
  raw = _merge({"task": task, **_read_yaml(DEFAULTS)}, _task_yaml(task))
  for item in overrides:
    raw = apply_override(raw, item)
  return from_dict(raw)

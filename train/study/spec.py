"""A study's description: tasks x seeds x groups (algorithm, preset, config overrides, early stop)
x step budgets, read from YAML and validated against the tasks, presets and criteria it names;
expanded into one Cell (a `train.run` invocation) per combination."""

from __future__ import annotations

import dataclasses
import pathlib

from mjx_tracks.baselines import ALGO as BASELINE_ALGO, BASELINES, baselines_for
from mjx_tracks.envs.config import (ConfigError, apply_override, available_tasks, config_dir, load_config, load_yaml,
                                    parse_mapping, require, require_plain_name, show)
from mjx_tracks.limits import MAX_OVERRIDES, MAX_RETRIES, MAX_SEED, MAX_STEPS, MAX_STUDY_RUNS, MAX_TRIALS
from train.core.early_stop import NO_EARLY_STOP, criterion_name, parse_early_stop
from train.evaluation import EVAL_TRIALS, robustness_scenes, scene_config
from train.core.plan import DEFAULT_LIBRARY, LIBRARIES, probe_every_of
from train.core.run_record import seed_folder, several_stops, several_tasks
from train.core.presets import SB3, get_preset, with_hyperparams

STUDY_DEFAULTS = {"retries": 1, "eval_trials": EVAL_TRIALS, "compare": [], "baselines": list(BASELINES),
                  "robustness": False}
GROUP_DEFAULTS = {"preset": "gpu", "library": DEFAULT_LIBRARY, "early_stop": "", "set": [], "hp": [], "backend": "gpu", "budgets": "runs", "tasks": [],
                  "pack_seeds": False, "pack_tasks": False}
BACKENDS = ("gpu", "cpu")
BUDGETS = ("runs", "milestones")  # a run per step budget | one run of the largest, its policy exported at the others


@dataclasses.dataclass(frozen=True)
class GroupSpec:
  """Runs that differ only by task, seed and budget."""
  name: str
  algo: str  # ppo | sac
  preset: str  # train/core/presets.py
  library: str  # whose training loop (train.run --library)
  steps: tuple[int, ...]  # step budgets: one run each
  early_stop: str  # an --early-stop criterion, or "" for none
  set: tuple[str, ...]  # config overrides KEY=VALUE, after the preset's
  hp: tuple[str, ...]  # the preset's hyper-parameters KEY=VALUE (train.run --hp)
  backend: str  # gpu | cpu: the workers that run its cells (cpu: e.g. one-robot runs)
  budgets: str  # BUDGETS: runs | milestones
  tasks: tuple[str, ...]  # the study's tasks this group trains; empty: all of them
  pack_seeds: bool  # a run's seeds start as one program (train.run --seeds), one worker slot for all
  pack_tasks: bool  # with pack_seeds: the packs of its tasks too, where one program takes their differences as data


@dataclasses.dataclass(frozen=True)
class StudySpec:
  name: str
  tasks: tuple[str, ...]
  seeds: tuple[int, ...]
  groups: tuple[GroupSpec, ...]
  retries: int  # attempts after a failed one, each from the run's last checkpoint
  eval_trials: int  # trials per evaluation scene of every finished run
  compare: tuple[tuple[str, str], ...]  # task pairs (A, B): the report's probability that A beats B
  baselines: tuple[str, ...]  # mjx_tracks.baselines evaluated on each task they can drive, beside the groups
  robustness: bool  # every run and baseline also evaluated on the robustness suite (train.evaluate --robustness)


@dataclasses.dataclass(frozen=True)
class Cell:
  """One run of a study."""
  group: str
  task: str
  steps: int
  seed: int
  algo: str
  preset: str
  early_stop: str
  overrides: tuple[str, ...]
  backend: str  # gpu | cpu: which workers run it
  milestones: tuple[int, ...] = ()  # smaller budgets whose policies this run exports and evaluates
  hp: tuple[str, ...] = ()  # train.run --hp KEY=VALUE
  library: str = DEFAULT_LIBRARY  # train.run --library
  robustness: bool = False  # its evaluation adds the robustness suite
  pack_seeds: bool = False  # its first attempt trains beside the other seeds of its pack in one program
  pack_tasks: bool = False  # ... and beside its group's other tasks where their configs allow (train.run --tasks)

  @property
  def id(self) -> str:
    return f"{self.group}/{self.task}/{self.steps}/s{self.seed}"

  @property
  def is_baseline(self) -> bool:
    """A baseline's evaluation (no training): its preset names the baseline."""
    return self.algo == BASELINE_ALGO

  def eval_args(self, trials: int) -> list[str]:
    """`python -m train.evaluate RUN` arguments of this cell's evaluation suite, less the database."""
    own = ["--baseline", self.preset, "--task", self.task] if self.is_baseline else []
    return [*own, "--suite", "--trials", str(trials)] + (["--milestones"] if self.milestones else []) + \
        (["--robustness"] if self.robustness else [])

  def train_args(self) -> list[str]:
    """`python -m train.run` arguments of this cell, less its run folder and database."""
    args = ["--task", self.task, "--algo", self.algo, "--preset", self.preset, "--steps", str(self.steps),
            "--seed", str(self.seed)]
    for item in self.overrides:
      args += ["--set", item]
    for item in self.hp:
      args += ["--hp", item]
    if self.library != DEFAULT_LIBRARY:
      args += ["--library", self.library]
    if self.milestones:
      args += ["--milestones", ",".join(map(str, self.milestones))]
    return args + ["--early-stop", stop_of(self)]  # the group's, not the preset's

  def config(self):
    """The run's task config (run_config)."""
    return run_config(self.task, self.algo, self.preset, self.library, self.overrides)

  @property
  def pack_key(self) -> "Cell":
    """What the cells of one pack share: everything but the seed."""
    return dataclasses.replace(self, seed=0)

  def budgets(self) -> tuple[int, ...]:
    """The step budgets this run's evaluations stand for."""
    return (*self.milestones, self.steps)

  def run_args(self, out: str, db: str) -> list[str]:
    return [*self.train_args(), "--out", out, "--db", db]


def _group(raw, i: int) -> GroupSpec:
  key = f"groups[{i}]"
  require(isinstance(raw, dict), key, lambda: f"must be a mapping, got {show(raw)}")
  g = parse_mapping(GroupSpec, {**GROUP_DEFAULTS, **raw}, key)
  require_plain_name(g.name, f"{key}.name")
  try:
    with_hyperparams(get_preset(g.algo, g.preset, g.library), g.hp)
  except ValueError as e:
    raise ConfigError(f"{key}: {e}") from None
  require(bool(g.steps) and all(1 <= n <= MAX_STEPS for n in g.steps), f"{key}.steps",
          f"one or more budgets from 1 to {MAX_STEPS:,}")
  require(len(g.set) <= MAX_OVERRIDES, f"{key}.set", f"at most {MAX_OVERRIDES} overrides")
  require(g.library in LIBRARIES, f"{key}.library", lambda: f"one of {tuple(LIBRARIES)}, got {show(g.library)}")
  require(g.library == DEFAULT_LIBRARY or (g.budgets == "runs" and (not g.early_stop or (
      g.library == SB3 and g.early_stop.startswith("return")))), f"{key}.library",
          f"{g.library} has no early stop (but sb3's return) and no milestones: {LIBRARIES[g.library]}")
  require(len(g.hp) <= MAX_OVERRIDES, f"{key}.hp", f"at most {MAX_OVERRIDES} hyper-parameters")
  require(g.backend in BACKENDS, f"{key}.backend", lambda: f"one of {BACKENDS}, got {show(g.backend)}")
  require(g.budgets in BUDGETS, f"{key}.budgets", lambda: f"one of {BUDGETS}, got {show(g.budgets)}")
  require(not g.pack_seeds or g.library == DEFAULT_LIBRARY, f"{key}.pack_seeds",
          f"packs seeds into one program of this project's trainer; {g.library} trains one run per process")
  require(not g.pack_tasks or g.pack_seeds, f"{key}.pack_tasks", "joins packs of seeds: set pack_seeds: true too")
  require(g.budgets == "runs" or not g.early_stop, f"{key}.budgets",
          "milestones stand for smaller budgets of one run; an early stop would cut them short")
  return g


def _check_tasks(spec: StudySpec) -> None:
  for task in spec.tasks:
    require(task in available_tasks(), "tasks", lambda: f"unknown task {show(task)}; known: {available_tasks()}")
  for i, g in enumerate(spec.groups):
    require(len(set(g.tasks)) == len(g.tasks) and set(g.tasks) <= set(spec.tasks), f"groups[{i}].tasks",
            lambda: f"distinct tasks of the study's tasks {list(spec.tasks)}, got {show(list(g.tasks))}")


def group_tasks(spec: StudySpec, g: GroupSpec) -> tuple[str, ...]:
  """The tasks a group trains: its own list, else the study's."""
  return g.tasks or spec.tasks


def run_config(task: str, algo: str, preset: str, library: str, overrides: tuple[str, ...]):
  """A run's task config: the task's with its preset's overrides, then its group's (as train.run's plan)."""
  return load_config(task, tuple(get_preset(algo, preset, library).config_overrides) + tuple(overrides))


def _check_runs(spec: StudySpec) -> None:
  """Every task's config takes every group's overrides and early stop."""
  for i, g in enumerate(spec.groups):
    for task in group_tasks(spec, g):
      try:
        cfg = run_config(task, g.algo, g.preset, g.library, g.set)
        if g.early_stop:
          parse_early_stop(g.early_stop, cfg)
        if spec.robustness:  # its cases fit the task (e.g. a latency of at most a control period)
          for scene in robustness_scenes(cfg):
            scene_config(cfg, scene)
      except ValueError as e:  # ConfigError included
        raise ConfigError(f"groups[{i}] ({g.name}) on {task}: {e}", getattr(e, "key", None)) from None


def study_from_dict(raw: dict) -> StudySpec:
  """A validated StudySpec from a plain mapping."""
  require(isinstance(raw, dict), "study", "the top level must be a mapping")
  raw = {**STUDY_DEFAULTS, **raw}
  groups = raw.get("groups")
  require(isinstance(groups, list) and bool(groups), "groups", "must be a non-empty list")
  spec = parse_mapping(StudySpec, {**raw, "groups": []}, "")
  spec = dataclasses.replace(spec, groups=tuple(_group(g, i) for i, g in enumerate(groups)))
  require_plain_name(spec.name, "name")
  names = [g.name for g in spec.groups]
  require(len(set(names)) == len(names), "groups", f"group names repeat: {names}")
  require(bool(spec.tasks) and bool(spec.seeds), "tasks / seeds", "each needs one or more entries")
  require(len(set(spec.seeds)) == len(spec.seeds) and 0 <= min(spec.seeds) and max(spec.seeds) <= MAX_SEED, "seeds",
          f"distinct integers from 0 to {MAX_SEED}")
  require(0 <= spec.retries <= MAX_RETRIES, "retries", f"from 0 to {MAX_RETRIES}")
  require(1 <= spec.eval_trials <= MAX_TRIALS, "eval_trials", f"from 1 to {MAX_TRIALS:,}")
  _check_tasks(spec)
  runs = len(spec.seeds) * sum(len(group_tasks(spec, g)) * len(runs_of(g)) for g in spec.groups)
  require(runs <= MAX_STUDY_RUNS, "study", f"{runs:,} runs; at most {MAX_STUDY_RUNS:,}")
  unknown = [b for b in spec.baselines if b not in BASELINES]
  require(not unknown and len(set(spec.baselines)) == len(spec.baselines), "baselines",
          lambda: f"distinct names of {list(BASELINES)}, got {show(list(spec.baselines))}")
  for i, pair in enumerate(spec.compare):
    require(pair[0] != pair[1] and set(pair) <= set(spec.tasks), f"compare[{i}]",
            lambda: f"two different tasks of the study, got {show(list(pair))}")
  _check_runs(spec)
  return spec


def study_text(path: str) -> str:
  """The YAML of a study file, or of a shipped study by NAME (configs/studies/NAME.yaml)."""
  p = pathlib.Path(path)
  if p.is_file():
    return p.read_text()
  shipped = config_dir().joinpath("studies", f"{path}.yaml")
  if shipped.is_file():
    return shipped.read_text()
  raise ConfigError(f"{path}: no such study file (nor a shipped study of that name)")


def load_study(path: str, overrides: tuple[str, ...] = ()) -> StudySpec:
  """A study file or shipped study NAME <- top-level KEY=VALUE overrides, validated."""
  raw = load_yaml(study_text(path), path) or {}
  for item in overrides:
    raw = apply_override(raw, item)
  return study_from_dict(raw)


def runs_of(g: GroupSpec) -> list[tuple[int, tuple[int, ...]]]:
  """(steps, milestones) of each run of a group: one per budget, or one with the smaller as milestones."""
  if g.budgets == "milestones":
    budgets = sorted(set(g.steps))
    return [(budgets[-1], tuple(budgets[:-1]))]
  return [(steps, ()) for steps in g.steps]


BASELINE_GROUP = "baseline-"  # + the baseline's name: the group of its cells


def packs_of(fresh: list[Cell]) -> list[list[Cell]]:
  """The packs among cells with nothing trained yet (two or more cells each, in order): those of a
  pack_seeds group that differ only in their seed; of a pack_tasks group, those packs joined across
  the group's tasks where they have the same seeds and one program takes their configs' differences
  as data (mjx_tracks.envs.task_data; train.run --tasks), task after task; then the packs of groups
  that differ only in their early stop (and name), with the same tasks and seeds, joined group after
  group (train.run --early-stops: the early stop is the host's, not the program's)."""
  packs: dict[Cell, list[Cell]] = {}
  for c in fresh:
    if c.pack_seeds and not c.is_baseline:
      packs.setdefault(c.pack_key, []).append(c)
  by_group = _joined(list(packs.values()), lambda q, p: p[0].pack_tasks and _joins(q, p))
  return [p for p in _joined(by_group, _same_but_stop) if len(p) > 1]


def _joined(packs: list[list[Cell]], joins) -> list[list[Cell]]:
  """The packs, each joined into the first earlier one that joins(earlier, it) allows."""
  joined: list[list[Cell]] = []
  for p in packs:
    home = next((q for q in joined if joins(q, p)), None)
    if home is None:
      joined.append(list(p))
    else:
      home.extend(p)
  return joined


def _joins(pack: list[Cell], seeds: list[Cell]) -> bool:
  """Whether a pack of one task's seeds may join a pack (its first task's) in one program."""
  from mjx_tracks.envs.task_data import packing_conflict  # noqa: PLC0415  (JAX: only where packs are formed)
  a, b = pack[0], seeds[0]
  return (dataclasses.replace(a.pack_key, task="") == dataclasses.replace(b.pack_key, task="")
          and [c.seed for c in pack if c.task == a.task] == [c.seed for c in seeds]
          and packing_conflict(a.config(), b.config()) is None)


def stop_of(cell: Cell) -> str:
  """A cell's early stop as train.run takes it (none for a group without one)."""
  return cell.early_stop or NO_EARLY_STOP


def _same_but_stop(pack: list[Cell], group: list[Cell]) -> bool:
  """Whether one group's pack may join a pack of other groups: the same runs (tasks, seeds, in order)
  under another early stop, everything else the same."""
  a, b = pack[0], group[0]
  first = [(c.task, c.seed) for c in pack if c.group == a.group]
  same = dataclasses.replace(a.pack_key, group="", early_stop="") == dataclasses.replace(b.pack_key, group="", early_stop="")
  return same and first == [(c.task, c.seed) for c in group] and _stops_apart(pack, group)


def _stopping(cell: Cell) -> tuple[str, int]:
  """(its criterion's name, its probe interval) as the cell's run will hold them (train.run's plan)."""
  cfg = cell.config()
  early = None if stop_of(cell) == NO_EARLY_STOP else parse_early_stop(stop_of(cell), cfg)
  preset = with_hyperparams(get_preset(cell.algo, cell.preset, cell.library), cell.hp)
  return criterion_name(early), probe_every_of(None, early, preset, cfg)


def _stops_apart(pack: list[Cell], group: list[Cell]) -> bool:
  """Whether a group's early stop is another criterion than each of a pack's on every task (two
  spellings of one criterion would give two runs one tag), with the probe interval of the pack's
  runs (an early stop on success probes its runs where the preset would not: one program holds
  runs of one interval)."""
  mine = {c.task: _stopping(c) for c in group if c.seed == group[0].seed}

  def apart(theirs: tuple[str, int], own: tuple[str, int]) -> bool:
    return theirs[0] != own[0] and theirs[1] == own[1]
  return all(apart(_stopping(c), mine[c.task]) for c in pack if c.seed == pack[0].seed)


def pack_train_args(pack: list[Cell]) -> list[str]:
  """`python -m train.run` arguments of a pack (packs_of), less its folder and database: its first
  cell's, with --seeds S,S,... for --seed (and --tasks T,T,... for --task where it spans several tasks,
  --early-stops C,C,... for --early-stop where it spans several early stops)."""
  def swapped(args: list[str], flag: str, plural: str, values) -> list[str]:
    i = args.index(flag)
    return [*args[:i], plural, ",".join(map(str, dict.fromkeys(values))), *args[i + 2:]]
  args = swapped(pack[0].train_args(), "--seed", "--seeds", (c.seed for c in pack))
  args = swapped(args, "--task", "--tasks", (c.task for c in pack)) if several_tasks(pack) else args
  stops = [stop_of(c) for c in pack]
  return swapped(args, "--early-stop", "--early-stops", stops) if several_stops(stops) else args


def pack_folders(pack: list[Cell]) -> list[str]:
  """Each cell's run folder in its pack's output folder (train.core.run_record.seed_folder)."""
  tasks, stops = several_tasks(pack), several_stops([stop_of(c) for c in pack])
  return [seed_folder("", c.seed, c.task if tasks else None, stop_of(c) if stops else None) for c in pack]


def cells(spec: StudySpec) -> list[Cell]:
  """The study's runs: group x task x budget x seed, in that order; then one evaluation of each
  baseline on each task it can drive (its trials vary by themselves; seed: the study's first)."""
  trained = [Cell(g.name, task, steps, seed, g.algo, g.preset, g.early_stop, g.set, g.backend, milestones, g.hp,
                  g.library, spec.robustness, g.pack_seeds, g.pack_tasks)
             for g in spec.groups for task in group_tasks(spec, g) for steps, milestones in runs_of(g)
             for seed in spec.seeds]
  return trained + [Cell(BASELINE_GROUP + name, task, 0, spec.seeds[0], BASELINE_ALGO, name, "", (), "gpu",
                         robustness=spec.robustness)
                    for task in spec.tasks for name in baselines_for(load_config(task), spec.baselines)]

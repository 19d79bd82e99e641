"""Evaluation as a library: the evaluation scenes of a task (its scene kind's, scenes.kinds), trial
rollouts of a policy compiled once, per-trial figures (mjx_tracks.metrics) and where reports go.
`python -m train.evaluate` (train/evaluate.py) is its command line; build, probe, studies, the
server and scripts import from here."""

from __future__ import annotations

import json
import os

import numpy as np

from mjx_tracks.envs.config import ConfigError, TaskConfig
from scenes.kinds import COMMON_SCENES, scene_kind
from scenes.kinds.base import replace_scene
from train.core.run_record import run_config  # noqa: F401  (the config a run recorded: part of this library)

SCENES = ("hardest", *COMMON_SCENES)  # the plain scene names (a task's kind adds prefixed ones)


def suite_scenes(cfg: TaskConfig) -> list[str]:
  """A study's evaluation suite: its scene kind's (scenes.kinds)."""
  return scene_kind(cfg.scene.kind).suite(cfg)


ROBUST = "+"  # BASE+CASE: an evaluation scene under one case of the robustness suite (evaluation.robustness)


def robustness_bases(cfg: TaskConfig) -> list[str]:
  """The scenes the robustness suite runs its cases on: hardest (where the task has one), uniform."""
  return (["hardest"] if cfg.scene.has_hardest else []) + ["uniform"]


def robustness_scenes(cfg: TaskConfig) -> list[str]:
  """The robustness suite: every case of evaluation.robustness on each of robustness_bases."""
  return [f"{base}{ROBUST}{case.name}" for base in robustness_bases(cfg) for case in cfg.evaluation.robustness]


def perturbed(cfg: TaskConfig, case_name: str) -> TaskConfig:
  """The task on the nominal robot (randomization on, every key at NOMINAL; no hidden rays), then one
  robustness case's overrides: one perturbation alone, whatever the policy trained with (and at
  any eps: grow off)."""
  from mjx_tracks.envs.config import apply_override, from_dict  # noqa: PLC0415
  from mjx_tracks.envs.randomization import nominal_section  # noqa: PLC0415
  case = next((c for c in cfg.evaluation.robustness if c.name == case_name), None)
  if case is None:
    raise ConfigError(f"unknown robustness case {case_name!r}; evaluation.robustness has "
                      f"{', '.join(c.name for c in cfg.evaluation.robustness) or '(none)'}")
  raw = cfg.to_dict()
  raw["randomization"] = nominal_section(raw["randomization"])  # grow off: a case's values as written, whatever eps
  raw["observation"]["noise"] = 0.0
  for item in case.set:
    raw = apply_override(raw, item)
  return from_dict(raw)


def scene_config(cfg: TaskConfig, scene: str) -> TaskConfig:
  """The task with its scenes drawn as an evaluation scene says: uniform, incremental or train
  (any kind), or one of its scene kind's own (hardest, HELD_OUT + NAME, ...; scenes.kinds), or
  BASE+CASE (one of those under a robustness case); every trial's start varied by
  evaluation.trial_variation, so that trials are samples."""
  if ROBUST in scene:
    base, _, case = scene.partition(ROBUST)
    return perturbed(scene_config(cfg, base), case)
  if scene in COMMON_SCENES:
    drawn = cfg if scene == "train" else replace_scene(cfg, sampler=scene)
  else:
    drawn = scene_kind(cfg.scene.kind).pinned(cfg, scene)
  if drawn is None:
    raise ConfigError(f"unknown scene {scene!r} for a {cfg.scene.kind} task: one of {', '.join(COMMON_SCENES)} or "
                      f"its suite's {', '.join(s for s in suite_scenes(cfg) if s not in COMMON_SCENES) or '(none)'}")
  return replace_scene(drawn, start_jitter=cfg.evaluation.trial_variation)


EVAL_TRIALS = 100  # trials of an evaluation (and of the in-training hardest probe)
EVAL_SEED = 1  # their reset keys: jax.random.split(PRNGKey(EVAL_SEED), trials)
EVAL_EPS = 1.0  # the difficulty handed to reset (pinned scenes such as hardest ignore it)


def live_steps(done) -> np.ndarray:
  """(steps, trials) bool of a rollout's per-step done flags (steps, trials): the steps up to and
  including each trial's first done step (all, where none): the steps its episode lasted."""
  done = np.asarray(done) > 0
  steps = done.shape[0]
  end = np.where(done.any(axis=0), done.argmax(axis=0), steps - 1)  # the last step of each episode
  return np.arange(steps)[:, None] <= end[None, :]


def largest_per_trial(cfg: TaskConfig, scene: str, make_act, measure, trials: int) -> np.ndarray:
  """(trials,): each trial's largest measure(state before, state after) (batched) over the control
  steps its episode lasts (0 where larger), on evaluation scene `scene` of task cfg, the actions of
  make_act(env)(states), for cfg.episode.max_steps steps; the evaluation's own trials (trial_keys,
  trial_starts). The physics checks of train.bench (the gate's launch check, contacts) measure with it."""
  import jax  # noqa: PLC0415
  env, draw = scene_env(cfg, scene)
  act = make_act(env)

  def rollout(keys):
    def body(s, _):
      after = jax.vmap(env.step)(s, act(s))
      return after, (measure(s, after), after.done)
    _, (value, done) = jax.lax.scan(body, trial_starts(env, keys, EVAL_EPS, None, draw), None,
                                    length=cfg.episode.max_steps)
    return value, done

  value, done = jax.jit(rollout)(trial_keys(trials))
  return np.where(live_steps(done), np.asarray(value), 0).max(axis=0)


def start_sums(state, trials: int) -> dict:
  """Per-trial sums of a batch state before its first step: every METRICS sum and the length 0, the
  final chassis position the start."""
  import jax.numpy as jnp  # noqa: PLC0415

  from mjx_tracks.metrics import STEP_NAMES  # noqa: PLC0415
  return {**{k: jnp.zeros(trials) for k in STEP_NAMES}, "length": jnp.zeros(trials),
          "final_pos": state.pipeline_state.data.qpos[:, :3]}


def add_step(acc: dict, state, active):
  """acc with one step of a batch state added for the trials still active (bool (trials,))."""
  import jax.numpy as jnp  # noqa: PLC0415

  from mjx_tracks.metrics import STEP_NAMES  # noqa: PLC0415
  a = active.astype(jnp.float32)
  return {**{k: acc[k] + a * state.metrics[k] for k in STEP_NAMES}, "length": acc["length"] + a,
          "final_pos": jnp.where(active[:, None], state.pipeline_state.data.qpos[:, :3], acc["final_pos"])}


def trial_starts(core, keys, eps: float, perturbations=None, draw=None):
  """Every trial's first state, as an evaluation draws it: `core.reset_at` of each trial's key at
  difficulty eps with the penalty normalizer at 1 (nothing learnt), each trial's perturbation and
  the scene draw where given (train.onnx_drive and scripts/analysis draw the same trials)."""
  import jax  # noqa: PLC0415
  import jax.numpy as jnp  # noqa: PLC0415
  reset = jax.vmap(core.reset_at, in_axes=(0, None, None, 0, None))
  return reset(keys, jnp.float32(eps), jnp.float32(1.0), perturbations, draw)


def trial_rollout(cfg: TaskConfig, make_act, trials: int, eps: float, observe=lambda s: s.obs, core=None):
  """(core, rollout): the task env and a pure rollout(params, keys[, perturbations[, draw]]) ->
  (sums, qpos of trial 0 per step, trial 0's scene), one episode per trial from
  `core.reset_at(key, eps)` (with each trial's perturbation and the scene draw, if given) with
  actions `make_act(params)(observe(state))` (a policy sees the observation; a scripted controller
  may see the whole state); sums holds each trial's METRICS sums, length and final chassis
  position. core: the env (default TrackedRobotEnv(cfg))."""
  import jax  # noqa: PLC0415
  import jax.numpy as jnp  # noqa: PLC0415

  from mjx_tracks.envs.task_env import TrackedRobotEnv  # noqa: PLC0415
  core = TrackedRobotEnv(cfg) if core is None else core

  def rollout(params, keys, perturbations=None, draw=None):
    act = make_act(params)
    s = trial_starts(core, keys, eps, perturbations, draw)

    def body(carry, _):
      s, acc, active = carry
      s = jax.vmap(core.step)(s, act(observe(s)))
      return (s, add_step(acc, s, active), active & (s.done == 0)), s.pipeline_state.data.qpos[0]

    (_, acc, _), qpos = jax.lax.scan(body, (s, start_sums(s, trials), jnp.ones(trials, bool)), None,
                                     length=cfg.episode.max_steps)
    scene0 = jax.tree_util.tree_map(lambda x: x[0], s.pipeline_state.scene)
    return acc, jnp.concatenate([s.pipeline_state.data.qpos[:1], qpos]), scene0

  return core, rollout


def scene_programs(cfg0: TaskConfig, scenes: list[str]) -> list[tuple[TaskConfig, dict]]:
  """[(the config of one compiled program, {scene: its draw})] evaluating task cfg0's scenes:
  scenes whose configs (scene_config) differ only in the keys their kind takes as data
  (SceneKind.drawn: sampler, ranges, the sub-kinds drawn) share one program and pass their draw;
  any other scene (a navigation area of another world) gets a program of its own."""
  import dataclasses  # noqa: PLC0415
  kind = scene_kind(cfg0.scene.kind)
  groups: list[tuple[TaskConfig, list[tuple[str, TaskConfig]]]] = []
  for scene in scenes:
    cfg = scene_config(cfg0, scene)
    key = replace_scene(cfg, **{k: getattr(cfg0.scene, k) for k in kind.drawn})
    members = next((m for k, m in groups if k == key), None)
    if members is None:
      groups.append((key, members := []))
    members.append((scene, cfg))
  out = []
  for key, members in groups:
    program = dataclasses.replace(key, scene=kind.program_section(key.scene, [c.scene for _, c in members]))
    out.append((program, {scene: kind.draw(c.scene, program.scene) for scene, c in members}))
  return out


def scene_env(cfg0: TaskConfig, scene: str):
  """(env, draw): the task env of the one program that evaluates `scene` of task cfg0
  (scene_programs) and the scene's draw, for replaying its trials (trial_starts with trial_keys)."""
  from mjx_tracks.envs.task_env import TrackedRobotEnv  # noqa: PLC0415
  ((cfg, draws),) = scene_programs(cfg0, [scene])
  return TrackedRobotEnv(cfg), draws[scene]


def trial_keys(trials: int, seed: int = EVAL_SEED):
  import jax  # noqa: PLC0415
  return jax.random.split(jax.random.PRNGKey(seed), trials)


def per_trial_figures(acc) -> dict:
  """Per-trial figures (mjx_tracks.metrics.EPISODE) and final chassis position from rollout sums."""
  from mjx_tracks.metrics import episode_figures  # noqa: PLC0415
  acc = {k: np.asarray(v) for k, v in acc.items()}
  final = acc["final_pos"]
  return {**episode_figures(acc, acc["length"]), "final_x": final[:, 0], "final_y": final[:, 1], "final_z": final[:, 2]}


def trial_runner(cfg0: TaskConfig, scenes: list[str], make_act, trials: int, eps: float, seed: int,
                 record: bool = False, observe=lambda s: s.obs):
  """run(params, scene) -> (per-trial figures with each trial's final chassis position, qpos of
  trial 0 at every step and a C model of its scene if record) on any of `scenes` (evaluation
  scenes of task cfg0): compiled once per program of scene_programs (one for every scene of a stair
  task), for every policy of one network."""
  import jax  # noqa: PLC0415
  keys = trial_keys(trials, seed)
  programs = {}
  for cfg, draws in scene_programs(cfg0, scenes):
    core, rollout = trial_rollout(cfg, make_act, trials, eps, observe)
    compiled = jax.jit(rollout)
    programs.update({scene: (core, compiled, draw) for scene, draw in draws.items()})

  def run(params, scene: str):
    core, compiled, draw = programs[scene]
    acc, qpos, scene0 = compiled(params, keys, None, draw)
    # trial 0's scene in a C model, for rendering its recorded qpos
    render_model = core.sim.c_model_with_boxes(scene0.box_pos, scene0.box_size, scene0.box_yaw) if record else None
    return per_trial_figures(acc), (np.asarray(qpos) if record else None), render_model

  def compile_for(params, scene: str):
    """The scene's program compiled for params like these, ahead of run (train.core.ahead)."""
    _, compiled, draw = programs[scene]
    return compiled.lower(params, keys, None, draw).compile()

  run.compile_for = compile_for
  return run


def group_trial_runner(cfg0: TaskConfig, scene: str, make_act, trials: int, eps: float, seed: int,
                       configs: list[TaskConfig] | None = None):
  """run(params with a leading run axis) -> [per-trial figures of each run]: pack_trial_runner on
  one scene (the runs of one `train.run --seeds` program probed at once; on the CPU
  policy_by_policy_runner: vmapped_trials)."""
  run = policies_runner(cfg0, [scene], make_act, trials, eps, seed, configs)

  def one(params):
    return run(params, scene)
  one.compile_for = lambda params: run.compile_for(params, scene)
  return one


# Environments one call of an evaluation program steps at most (policies x trials): a pack's policies
# beyond it go through the same program in chunks (policies_per_call). A GPU's memory bounds a batch;
# the paper study's PPO program trains 20 x 4,096 = 81,920 robots on one, and its pack's final
# evaluation is 80 policies x 100 trials = 8,000, within one call.
EVAL_ENVS_PER_CALL = 32_768


def policies_per_call(policies: int, trials: int) -> int:
  """How many policies' trials one call of pack_trial_runner's program takes: all of them, or as
  many as EVAL_ENVS_PER_CALL holds (at least one)."""
  return min(policies, max(1, EVAL_ENVS_PER_CALL // trials))


def _policies(params) -> int:
  """How many policies params hold (their leading axis)."""
  import jax  # noqa: PLC0415
  return len(jax.tree_util.tree_leaves(params)[0])


def _in_chunks(fn, params, data, size: int, per_policy_data: bool):
  """fn(params, data)'s figures over the leading policy axis, `size` policies a call; the last call
  filled up with copies of the last policy (one compiled program for every call), dropped after."""
  import jax  # noqa: PLC0415
  n = _policies(params)
  if size >= n:
    return fn(params, data)
  calls = []
  for start in range(0, n, size):
    rows = np.minimum(np.arange(start, start + size), n - 1)
    acc = fn(jax.tree_util.tree_map(lambda x, r=rows: x[r], params),
             jax.tree_util.tree_map(lambda x, r=rows: x[r], data) if per_policy_data else data)
    calls.append({k: np.asarray(v)[:min(size, n - start)] for k, v in acc.items()})
  return {k: np.concatenate([c[k] for c in calls]) for k in calls[0]}


def pack_trial_runner(cfg0: TaskConfig, scenes: list[str], make_act, trials: int, eps: float, seed: int,
                      configs: list[TaskConfig] | None = None):
  """run(params with a leading policy axis, scene) -> [per-trial figures of each policy]:
  trial_runner's trials on any of `scenes` for several policies of one network in one program (the
  rollout vmapped over the policies; at most policies_per_call a call), compiled once per program
  of scene_programs (one for every scene of a stair task). configs: each policy's task where they
  differ (mjx_tracks.envs.task_data: runs that may share a program); each policy's trials are then
  those of the scene of its own task (its stair direction, its reward's safety term). A policy's
  trials are those trial_runner gives it alone: the same keys, starts and scenes (floats within the
  vmap's rounding)."""
  import jax  # noqa: PLC0415

  from mjx_tracks.envs.task_data import stacked, task_data  # noqa: PLC0415
  from mjx_tracks.envs.task_env import TrackedRobotEnv  # noqa: PLC0415
  keys = trial_keys(trials, seed)
  programs = {}
  for cfg, draws in scene_programs(cfg0, scenes):
    core = TrackedRobotEnv(cfg)
    if configs is None:
      _, rollout = trial_rollout(cfg, make_act, trials, eps, core=core)
      compiled = jax.jit(jax.vmap(lambda params, draw, rollout=rollout: rollout(params, keys, None, draw)[0],
                                  in_axes=(0, None)))
      programs.update({scene: (compiled, draw) for scene, draw in draws.items()})
      continue

    def each(params, task, cfg=cfg, core=core):
      _, rollout = trial_rollout(cfg, make_act, trials, eps, core=core.for_task(task))
      return rollout(params, keys, None, task.draw)[0]
    compiled = jax.jit(jax.vmap(each))
    # each run's task: its scene's config in this program (scene_programs), as data
    programs.update({scene: (compiled, stacked([task_data(scene_config(c, scene), cfg) for c in configs]))
                     for scene in draws})

  def size(params) -> int:
    return policies_per_call(_policies(params), trials)

  def run(params, scene: str) -> list[dict]:
    compiled, data = programs[scene]
    acc = _in_chunks(compiled, params, data, size(params), configs is not None)
    return [per_trial_figures({k: v[i] for k, v in acc.items()}) for i in range(len(acc["length"]))]

  def compile_for(params, scene: str):
    """The scene's program compiled for params like these (a call's worth), ahead of run (train.core.ahead)."""
    compiled, data = programs[scene]
    first = lambda tree: jax.tree_util.tree_map(lambda x: x[:size(params)], tree)  # noqa: E731
    return compiled.lower(first(params), first(data) if configs is not None else data).compile()

  run.compile_for = compile_for
  return run


def policies_runner(cfg0: TaskConfig, scenes: list[str], make_act, trials: int, eps: float, seed: int,
                    configs: list[TaskConfig] | None = None):
  """run(params with a leading policy axis, scene) -> [per-trial figures of each policy]:
  pack_trial_runner's, or on the CPU policy_by_policy_runner's (vmapped_trials)."""
  runner = pack_trial_runner if vmapped_trials() else policy_by_policy_runner
  return runner(cfg0, scenes, make_act, trials, eps, seed, configs)


def vmapped_trials() -> bool:
  """Whether several policies' trials run vmapped in one program (pack_trial_runner) rather than
  one policy after another (policy_by_policy_runner): not on the CPU, where a vmapped program gains
  nothing over the cores it already uses, and where jaxlib 0.10.2's runtime stalls for good (no
  core busy) on pack_trial_runner's rollout of 4 policies x 100 trials of two tasks (a GroupProbe of
  4 one-robot runs of two tasks hangs the same way during training: 2026-11-28, this 2-core machine)."""
  import jax  # noqa: PLC0415
  return jax.default_backend() != "cpu"


def policy_by_policy_runner(cfg0: TaskConfig, scenes: list[str], make_act, trials: int, eps: float, seed: int,
                            configs: list[TaskConfig] | None = None):
  """pack_trial_runner's run(params with a leading policy axis, scene), one policy after another,
  each through trial_runner of its own task (compiled once per task, for every policy of it)."""
  import jax  # noqa: PLC0415
  runners: list = []  # (config, its trial_runner): configs compare by value

  def runner(cfg):
    found = next((r for c, r in runners if c == cfg), None)
    if found is None:
      runners.append((cfg, found := trial_runner(cfg, scenes, make_act, trials, eps, seed)))
    return found

  def each(params) -> list[tuple[TaskConfig, object]]:
    n = _policies(params)
    return list(zip(configs or [cfg0] * n, (jax.tree_util.tree_map(lambda x, i=i: x[i], params) for i in range(n))))

  def run(params, scene: str) -> list[dict]:
    return [runner(cfg)(p, scene)[0] for cfg, p in each(params)]

  def compile_for(params, scene: str) -> None:
    """The scene's program of each task compiled for params like these, ahead of run (train.core.ahead;
    once a task: its policies share it)."""
    done: list[TaskConfig] = []
    for cfg, p in each(params):
      if not any(c == cfg for c in done):
        done.append(cfg)
        runner(cfg).compile_for(p, scene)

  run.compile_for = compile_for
  return run


def robustness_runner(cfg0: TaskConfig, bases: list[str], make_act, trials: int, eps: float, seed: int,
                      observe=lambda s: s.obs):
  """run(params, base) -> {case: per-trial figures}: every case of the robustness suite on scene
  `base` (one of bases), trials each, in one batch (the perturbations are data: TrackedRobotEnv
  every_path) and one program for the bases of one program of scene_programs. Every case sees the
  same scenes and starts (common random numbers: paired trials)."""
  import jax  # noqa: PLC0415
  import jax.numpy as jnp  # noqa: PLC0415

  from mjx_tracks.envs.randomization import task_draw  # noqa: PLC0415
  from mjx_tracks.envs.task_env import TrackedRobotEnv  # noqa: PLC0415
  names = [c.name for c in cfg0.evaluation.robustness]
  keys = trial_keys(trials, seed)
  programs = {}
  for cfg, draws in scene_programs(cfg0, bases):
    cases = [perturbed(cfg, name) for name in names]
    core = TrackedRobotEnv(cases[0], every_path=True)
    perts = [jax.vmap(lambda k, c=c: task_draw(c, k, jnp.float32(eps), core.sim.layout.n_joints))(keys) for c in cases]
    perts = jax.tree_util.tree_map(lambda *x: jnp.concatenate(x), *perts)
    _, rollout = trial_rollout(cases[0], make_act, trials * len(cases), eps, observe, core)
    compiled = jax.jit(rollout)
    programs.update({base: (compiled, perts, draw) for base, draw in draws.items()})
  all_keys = jnp.tile(keys, (len(names), 1))

  def run(params, base: str):
    compiled, perts, draw = programs[base]
    acc, _, _ = compiled(params, all_keys, perts, draw)
    figures = per_trial_figures(acc)
    return {name: {k: v[i * trials:(i + 1) * trials] for k, v in figures.items()} for i, name in enumerate(names)}

  return run


def milestone_folder(budget: int) -> str:
  """Where a run exports its policy at a step budget (train.run --milestones), inside its folder."""
  return os.path.join("milestones", str(budget))


def saved_milestones(run_dir: str) -> list[int]:
  """The budgets a run exported a policy at, ascending."""
  path = os.path.join(run_dir, "milestones")
  return sorted(int(d) for d in os.listdir(path) if d.isdigit()) if os.path.isdir(path) else []


def report_path(run_dir: str, scene: str, budget: int | None) -> str:
  """RUN/eval-<scene>[@<budget>].json (a held-out scene's / becomes -)."""
  at = "" if budget is None else f"@{budget}"
  return os.path.join(run_dir, f"eval-{scene.replace('/', '-')}{at}.json")


def trials_in(path: str) -> int | None:
  """The trial count of the report at path, if one is there and readable."""
  try:
    with open(path) as f:
      return int(json.load(f)["trials"])
  except (OSError, ValueError, KeyError, TypeError):
    return None


def fewer_trials_path(path: str, trials: int) -> str:
  """Where a report of fewer trials than the one at path goes: eval-<scene>.<N>-trials.json."""
  return f"{path[:-len('.json')]}.{trials}-trials.json"

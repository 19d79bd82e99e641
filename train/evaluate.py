"""`python -m train.evaluate RUN_DIR --trials 100 --scene hardest`: run a trained policy.

Scenes: hardest (every staircase parameter at its hard end of the task's ranges: n = n_max,
l = l_min, h = h_max, the paper's highest complexity, 7 x 0.35 x 0.22 m by default; for terrain
tasks every parameter of each kind), uniform (the task's ranges, uniform), incremental (the task's
sampler at --eps), train (the task's own sampler at --eps), held-out/NAME (a fixed staircase of the
task's evaluation.held_out), hardest/KIND (a terrain task's kind KIND alone, at its hardest),
nav/KIND (a navigation task's area kind KIND alone: hallway or zigzag);
--suite runs the evaluation suite (suite_scenes). Trials run in parallel, one episode
each, deterministic policy: the exported RUN_DIR/policy, those exported at milestone budgets too
(--milestones), or with --checkpoint [STEP] a training checkpoint (a killed run has no export yet).
Writes RUN_DIR/eval-<scene>[@<budget>].json (mean +- std of progress, success, COG deviation,
|pitch rate|, tip-overs, episode length) and one database row per trial.
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import json
import os
import sys

import numpy as np

from mjx_tracks.envs.config import ConfigError, SceneConfig, TaskConfig, from_dict
from mjx_tracks.limits import MAX_SEED, MAX_TRIALS
from scenes.staircase import STAIR_HARD, STAIR_PARAMS
from scenes.terrain_kinds import TERRAIN_PARAMS

SCENES = ("hardest", "uniform", "incremental", "train")


HELD_OUT = "held-out/"  # scene name prefix of the fixed held-out staircases / terrains (evaluation.held_out[_terrain])
HARDEST = "hardest/"  # scene name prefix of one terrain kind's hardest configuration (terrain tasks)
NAV = "nav/"  # scene name prefix of one navigation area kind (nav tasks)


def suite_scenes(cfg: TaskConfig) -> list[str]:
  """A study's evaluation suite: hardest, uniform and each held-out staircase (stair tasks); hardest,
  uniform and, with several kinds, each kind's hardest (terrain tasks); uniform (nav)."""
  s = cfg.scene
  if s.kind == "terrain":
    return ["hardest", "uniform", *((HARDEST + k for k in s.terrains) if len(s.terrains) > 1 else ()),
            *(HELD_OUT + h.name for h in cfg.evaluation.held_out_terrain if h.kind in s.terrains)]
  if s.kind == "nav":
    return ["uniform", *((NAV + k for k in s.nav_kinds) if len(s.nav_kinds) > 1 else ())]
  return ["hardest", "uniform", *(HELD_OUT + h.name for h in cfg.evaluation.held_out)]


def _held_out(cfg: TaskConfig, scene: str) -> TaskConfig:
  """The task with every episode on one held-out staircase (or terrain, of a kind it draws)."""
  s, terrain = cfg.scene, cfg.scene.kind == "terrain"
  named = ({h.name: h for h in cfg.evaluation.held_out_terrain if h.kind in s.terrains} if terrain
           else {h.name: h for h in cfg.evaluation.held_out})
  h = named.get(scene[len(HELD_OUT):])
  if h is None:
    field = "held_out_terrain (of the kinds it draws)" if terrain else "held_out"
    raise ConfigError(f"scene {scene!r}: the task's evaluation.{field} names {sorted(named) or 'none'}")
  if terrain:
    return dataclasses.replace(cfg, scene=_pinned_terrain(s, h.kind, h.values))
  pinned = {name: (getattr(h, name),) * 2 for name in STAIR_PARAMS}
  return dataclasses.replace(cfg, scene=dataclasses.replace(s, sampler="uniform", **pinned))


def _pinned_terrain(s: SceneConfig, kind: str, values) -> SceneConfig:
  """Terrain scenes of one kind with its parameters pinned to values (in the kind's order)."""
  ranges = dataclasses.replace(getattr(s.terrain, kind), **{n: (v, v) for n, v in zip(TERRAIN_PARAMS[kind].names, values)})
  return dataclasses.replace(s, sampler="uniform", terrains=(kind,), terrain=dataclasses.replace(s.terrain, **{kind: ranges}))


def _hardest_terrain(s: SceneConfig, kinds: tuple[str, ...]) -> SceneConfig:
  """Terrain scenes of the given kinds with every parameter of each at its hard end."""
  for kind in kinds:
    ranges, p = getattr(s.terrain, kind), TERRAIN_PARAMS[kind]
    s = _pinned_terrain(s, kind, [getattr(ranges, n)[end == "high"] for n, end in zip(p.names, p.hard)])
  return dataclasses.replace(s, terrains=kinds)


def _hardest(s: SceneConfig, scene: str) -> SceneConfig:
  """hardest: every parameter at its hard end; hardest/KIND: a terrain task's kind KIND alone."""
  if not s.has_hardest:
    raise ConfigError(f"scene {scene!r} exists for stair and terrain tasks only")
  if s.kind == "terrain":
    kind = scene[len(HARDEST):] if scene.startswith(HARDEST) else None
    if kind is not None and kind not in s.terrains:
      raise ConfigError(f"scene {scene!r}: the task draws terrains {list(s.terrains)}")
    return _hardest_terrain(s, (kind,) if kind else s.terrains)
  if scene != "hardest":
    raise ConfigError(f"scene {scene!r}: {HARDEST}KIND is for terrain tasks")
  pinned = {name: (getattr(s, name)[end == "high"],) * 2  # each parameter at its hard end
            for name, end in zip(STAIR_PARAMS, STAIR_HARD)}
  return dataclasses.replace(s, sampler="uniform", **pinned)


def scene_config(cfg: TaskConfig, scene: str) -> TaskConfig:
  """The task with its scenes drawn as an evaluation scene says (SCENES, held-out/NAME or hardest/KIND)."""
  s = cfg.scene
  if scene.startswith(HELD_OUT):
    return _held_out(cfg, scene)
  if scene == "hardest" or scene.startswith(HARDEST):
    return dataclasses.replace(cfg, scene=_hardest(s, scene))
  if scene.startswith(NAV):
    kind = scene[len(NAV):]
    if s.kind != "nav" or kind not in s.nav_kinds:
      raise ConfigError(f"scene {scene!r}: the task draws navigation areas {list(s.nav_kinds) if s.kind == 'nav' else []}")
    return dataclasses.replace(cfg, scene=dataclasses.replace(s, nav_kinds=(kind,)))
  if scene not in SCENES:
    raise ConfigError(f"unknown scene {scene!r}: one of {SCENES}, {HELD_OUT}NAME, {HARDEST}KIND or {NAV}KIND")
  if scene in ("uniform", "incremental"):
    s = dataclasses.replace(s, sampler=scene)
  return dataclasses.replace(cfg, scene=s)


EVAL_TRIALS = 100  # trials of an evaluation (and of the in-training hardest probe)
EVAL_SEED = 1  # their reset keys: jax.random.split(PRNGKey(EVAL_SEED), trials)
EVAL_EPS = 1.0  # the difficulty handed to reset (pinned scenes such as hardest ignore it)


def trial_rollout(cfg: TaskConfig, make_act, trials: int, eps: float, observe=lambda s: s.obs):
  """(core, rollout): the task env and a pure rollout(params, keys) -> (sums, qpos of trial 0 per
  step, trial 0's scene), one episode per trial from `core.reset_at(key, eps)` with actions
  `make_act(params)(observe(state))` (a policy sees the observation; a scripted controller may see
  the whole state); sums holds each trial's METRICS sums, length and final chassis position."""
  import jax  # noqa: PLC0415
  import jax.numpy as jnp  # noqa: PLC0415

  from mjx_tracks.envs.task_env import METRICS, TrackedRobotEnv  # noqa: PLC0415
  core = TrackedRobotEnv(cfg)

  def rollout(params, keys):
    act = make_act(params)
    s = jax.vmap(core.reset_at, in_axes=(0, None, None))(keys, jnp.float32(eps), jnp.float32(1.0))
    acc0 = {**{k: jnp.zeros(trials) for k in METRICS}, "length": jnp.zeros(trials),
            "final_pos": s.pipeline_state.data.qpos[:, :3]}

    def body(carry, _):
      s, acc, active = carry
      s = jax.vmap(core.step)(s, act(observe(s)))
      a = active.astype(jnp.float32)
      acc = {**{k: acc[k] + a * s.metrics[k] for k in METRICS}, "length": acc["length"] + a,
             "final_pos": jnp.where(active[:, None], s.pipeline_state.data.qpos[:, :3], acc["final_pos"])}
      return (s, acc, active & (s.done == 0)), s.pipeline_state.data.qpos[0]

    (_, acc, _), qpos = jax.lax.scan(body, (s, acc0, jnp.ones(trials, bool)), None, length=cfg.episode.max_steps)
    scene0 = jax.tree_util.tree_map(lambda x: x[0], s.pipeline_state.scene)
    return acc, jnp.concatenate([s.pipeline_state.data.qpos[:1], qpos]), scene0

  return core, rollout


def run_config(run_dir: str) -> TaskConfig:
  """The task config a run recorded in RUN_DIR/run.json."""
  with open(os.path.join(run_dir, "run.json")) as f:
    return from_dict(json.load(f)["config"])


def trial_keys(trials: int, seed: int = EVAL_SEED):
  import jax  # noqa: PLC0415
  return jax.random.split(jax.random.PRNGKey(seed), trials)


def per_trial_figures(acc) -> dict:
  """Per-trial figures (mjx_tracks.envs.episode_stats) and final chassis position from rollout sums."""
  from mjx_tracks.envs.episode_stats import episode_figures  # noqa: PLC0415
  acc = {k: np.asarray(v) for k, v in acc.items()}
  final = acc["final_pos"]
  return {**episode_figures(acc, acc["length"]), "final_x": final[:, 0], "final_y": final[:, 1], "final_z": final[:, 2]}


def trial_runner(cfg: TaskConfig, make_act, trials: int, eps: float, seed: int, record: bool = False,
                 observe=lambda s: s.obs):
  """run(params) -> (per-trial figures with each trial's final chassis position, qpos of trial 0 at
  every step and a C model of its scene if record): compiled once, for every policy of one network."""
  import jax  # noqa: PLC0415
  core, rollout = trial_rollout(cfg, make_act, trials, eps, observe)
  compiled, keys = jax.jit(rollout), trial_keys(trials, seed)

  def run(params):
    acc, qpos, scene0 = compiled(params, keys)
    # trial 0's scene in a C model, for rendering its recorded qpos
    render_model = core.sim.c_model_with_boxes(scene0.box_pos, scene0.box_size, scene0.box_yaw) if record else None
    return per_trial_figures(acc), (np.asarray(qpos) if record else None), render_model

  return run


def _policy(run_dir: str, checkpoint: str | None, milestone: int | None = None):
  """(make_act, params, step) of the exported policy, of the one exported at a milestone budget, or
  of a checkpoint ('latest' or a step number)."""
  from train.policy import act_from_params, load_checkpoint_params, load_policy_info, load_policy_params  # noqa: PLC0415
  if checkpoint is None:
    policy_dir = os.path.join(run_dir, "policy" if milestone is None else milestone_folder(milestone))
    spec, params = load_policy_params(policy_dir)
    return act_from_params(spec), params, load_policy_info(policy_dir).get("step")
  if checkpoint != "latest" and not checkpoint.isdigit():
    raise ValueError(f"--checkpoint takes a step number (or nothing, for the latest), got {checkpoint!r}")
  spec, params, step = load_checkpoint_params(run_dir, None if checkpoint == "latest" else int(checkpoint))
  return act_from_params(spec), params, step


def milestone_folder(budget: int) -> str:
  """Where a run exports its policy at a step budget (train.run --milestones), inside its folder."""
  return os.path.join("milestones", str(budget))


def saved_milestones(run_dir: str) -> list[int]:
  """The budgets a run exported a policy at, ascending."""
  path = os.path.join(run_dir, "milestones")
  return sorted(int(d) for d in os.listdir(path) if d.isdigit()) if os.path.isdir(path) else []


def _record_trials(args: argparse.Namespace, run_id: str, scene: str, budget: int | None,
                   per_trial: dict) -> None:
  """One database row per trial, where the run is in the database."""
  from train.db import ExperimentDB, default_path  # noqa: PLC0415
  db = ExperimentDB(args.db or default_path(os.path.dirname(os.path.abspath(args.run_dir))))
  try:
    db.run(run_id)
  except KeyError:
    print(f"note: run {run_id} is not in {db.path}; trials not recorded there", file=sys.stderr)
    return
  db.log_evals(run_id, [
      {"scene": scene, "budget": budget, "trial": i, "progress": float(per_trial["progress"][i]),
       "success": int(per_trial["success"][i] > 0), "cog_deviation": float(per_trial["cog_deviation"][i]),
       "pitch_rate": float(per_trial["pitch_rate"][i]), "tipped_over": int(per_trial["tipped_over"][i] > 0),
       "length": int(per_trial["length"][i])} for i in range(args.trials)], replace=(scene, budget))


def parser() -> argparse.ArgumentParser:
  p = argparse.ArgumentParser(prog="python -m train.evaluate", description=__doc__.splitlines()[0])
  p.add_argument("run_dir")
  p.add_argument("--trials", type=int, default=EVAL_TRIALS)
  p.add_argument("--scene", default="hardest", help=f"one of {', '.join(SCENES)}, {HELD_OUT}NAME "
                 f"(a staircase of the task's evaluation.held_out) or {HARDEST}KIND (a terrain kind)")
  p.add_argument("--suite", action="store_true", help="every scene of the task's evaluation suite "
                 "(hardest, uniform, each held-out staircase or terrain kind) instead of --scene")
  p.add_argument("--eps", type=float, default=EVAL_EPS, help="difficulty for incremental / train scenes")
  p.add_argument("--seed", type=int, default=EVAL_SEED)
  p.add_argument("--out", help="report path (default RUN_DIR/eval-<scene>[@<budget>].json; one scene only)")
  p.add_argument("--db", help="experiment database (default: beside the run directory)")
  p.add_argument("--video", help="MP4 (needs the video extra) or, for a path ending .gif, GIF of trial 0 "
                 "until its episode ends (one scene only)")
  p.add_argument("--checkpoint", nargs="?", const="latest", metavar="STEP",
                 help="evaluate a training checkpoint (default the latest) instead of RUN_DIR/policy, "
                      "e.g. of a killed run")
  p.add_argument("--milestones", action="store_true", help="also evaluate the policy exported at each "
                 "milestone budget (train.run --milestones), RUN_DIR/milestones/<budget>")
  return p


def report_path(run_dir: str, scene: str, budget: int | None) -> str:
  """RUN/eval-<scene>[@<budget>].json (a held-out scene's / becomes -)."""
  at = "" if budget is None else f"@{budget}"
  return os.path.join(run_dir, f"eval-{scene.replace('/', '-')}{at}.json")


def _evaluate(args, meta: dict, scene: str, budgets: list[int | None], cfg0: TaskConfig) -> list[str]:
  """Runs one scene with the policy of each budget (one compilation); writes each report and its
  trials; returns the summary lines."""
  cfg = scene_config(cfg0, scene)
  policies = {b: _policy(args.run_dir, args.checkpoint, b) for b in budgets}
  print(f"{scene}: compiling and running {args.trials} trials of up to {cfg.episode.max_steps} steps "
        f"({len(budgets)} polic{'y' if len(budgets) == 1 else 'ies'}; the first time on this machine takes "
        "a minute or more) ...", file=sys.stderr, flush=True)
  run = trial_runner(cfg, policies[budgets[0]][0], args.trials, args.eps, args.seed, bool(args.video))
  lines = []
  for budget, (_, params, policy_step) in policies.items():
    per_trial, qpos, render_model = run(params)
    out = _write_report(args, meta, scene, budget, policy_step, per_trial)
    if args.video:
      from mjx_tracks.tools.render import camera_for, render_frames, write_video  # noqa: PLC0415
      shown = qpos[:int(per_trial["length"][0]) + 1]  # the reset, then trial 0 until its episode ended
      frames = render_frames(render_model, shown, **camera_for(cfg.scene.kind))
      write_video(args.video, frames, fps=1 / cfg.control.period)
    lines.append(_summary(meta["task"], scene, budget, args.trials, per_trial, out))
  return lines


def _write_report(args, meta: dict, scene: str, budget: int | None, policy_step, per_trial: dict) -> str:
  """RUN/eval-<scene>[@<budget>].json (or --out) and the database's trial rows; returns the path.
  A report of more trials already there is kept, with its rows: this one goes beside it
  (fewer_trials_path) and not to the database."""
  import jax  # noqa: PLC0415
  report = {
      "run_id": meta["run_id"], "task": meta["task"], "algo": meta["algo"], "scene": scene, "budget": budget,
      "eps": args.eps if scene in ("incremental", "train") else None,
      "trials": args.trials, "policy_step": policy_step, "checkpoint": args.checkpoint is not None,
      "metrics": {k: {"mean": float(v.mean()), "std": float(v.std())} for k, v in per_trial.items()},
      "per_trial": {k: v.tolist() for k, v in per_trial.items()},
      "device": str(jax.devices()[0]), "command": "python -m train.evaluate " + " ".join(args.argv),
      "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")}
  out = args.out or report_path(args.run_dir, scene, budget)
  fuller = None if args.out else _trials_in(out)
  if fuller is not None and fuller > args.trials:
    out = fewer_trials_path(out, args.trials)
    print(f"note: kept {report_path(args.run_dir, scene, budget)} ({fuller} trials) and its database rows; "
          f"this {args.trials}-trial result goes to {out} only", file=sys.stderr)
  with open(out, "w") as f:
    json.dump(report, f, indent=1)
  if fuller is None or fuller <= args.trials:
    _record_trials(args, meta["run_id"], scene, budget, per_trial)
  return out


def _trials_in(path: str) -> int | None:
  """The trial count of the report at path, if one is there and readable."""
  try:
    with open(path) as f:
      return int(json.load(f)["trials"])
  except (OSError, ValueError, KeyError, TypeError):
    return None


def fewer_trials_path(path: str, trials: int) -> str:
  """Where a report of fewer trials than the one at path goes: eval-<scene>.<N>-trials.json."""
  return f"{path[:-len('.json')]}.{trials}-trials.json"


def _summary(task: str, scene: str, budget: int | None, trials: int, per_trial: dict, out: str) -> str:
  m = {k: (float(v.mean()), float(v.std())) for k, v in per_trial.items()}
  at = "" if budget is None else f" @ {budget:,} steps"
  return (f"{task} {scene}{at}: {trials} trials, progress {m['progress'][0]:.3f} +- {m['progress'][1]:.3f}, "
          f"success {m['success'][0]:.2f}, COG deviation {m['cog_deviation'][0]:.3f} +- "
          f"{m['cog_deviation'][1]:.3f} m, |pitch rate| {m['pitch_rate'][0]:.3f} rad/s, tip-overs "
          f"{m['tipped_over'][0]:.2f}, length {m['length'][0]:.1f} -> {out}")


def _jobs(args, cfg: TaskConfig) -> list[tuple[str, list[int | None]]]:
  """(scene, milestone budgets with None for the final policy) to evaluate; ValueError on bad input."""
  scenes = suite_scenes(cfg) if args.suite else [args.scene]
  for scene in scenes:
    scene_config(cfg, scene)  # ConfigError on an unknown scene
  budgets: list[int | None] = [None]
  if args.milestones:
    if args.checkpoint is not None:
      raise ValueError("--milestones evaluates exported policies; drop --checkpoint")
    budgets = [*saved_milestones(args.run_dir), None]
  if len(scenes) * len(budgets) > 1 and (args.out or args.video):
    raise ValueError("--out and --video take one scene and one policy")
  return [(scene, budgets) for scene in scenes]


def _run_meta(run_json: str) -> dict:
  """A run's run.json; ValueError in one line if it is unreadable or not a run's record."""
  try:
    with open(run_json) as f:
      meta = json.load(f)
  except (OSError, ValueError) as e:
    raise ValueError(f"{run_json} is not readable JSON ({str(e).splitlines()[0][:120]})") from None
  missing = [k for k in ("run_id", "task", "algo", "config") if not isinstance(meta, dict) or k not in meta]
  if missing:
    raise ValueError(f"{run_json} is not a run's record (no {', '.join(missing)})")
  return meta


def main(argv: list[str] | None = None) -> int:
  args = parser().parse_args(argv)
  args.argv = sys.argv[1:] if argv is None else argv
  run_json = os.path.join(args.run_dir, "run.json")
  if not os.path.exists(run_json):
    print(f"error: {args.run_dir} is not a run directory (no run.json)", file=sys.stderr)
    return 2
  if not 1 <= args.trials <= MAX_TRIALS or not 0.0 <= args.eps <= 1.0 or not 0 <= args.seed <= MAX_SEED:
    print(f"error: --trials must be from 1 to {MAX_TRIALS:,}, --eps in [0, 1], --seed from 0 to {MAX_SEED}",
          file=sys.stderr)
    return 2
  from mjx_tracks import compile_cache  # noqa: PLC0415
  compile_cache.enable()
  try:
    meta = _run_meta(run_json)
    cfg = from_dict(meta["config"])
    for scene, budgets in _jobs(args, cfg):
      for line in _evaluate(args, meta, scene, budgets, cfg):
        print(line, flush=True)
  except (ConfigError, FileNotFoundError, ValueError) as e:
    print(f"error: {e}", file=sys.stderr)
    return 2
  return 0


if __name__ == "__main__":
  sys.exit(main())

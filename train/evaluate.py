"""`python -m train.evaluate RUN_DIR --trials 100 --scene hardest`: run a trained policy.

Scenes: hardest (every staircase parameter at its hard end of the task's ranges: n = n_max,
l = l_min, h = h_max, the paper's highest complexity, 7 x 0.35 x 0.22 m by default; for terrain
tasks every parameter of each kind), uniform (the task's ranges, uniform), incremental (the task's
sampler at --eps), train (the task's own sampler at --eps), held-out/NAME (a fixed staircase of the
task's evaluation.held_out), hardest/KIND (a terrain task's kind KIND alone, at its hardest),
nav/KIND (a navigation task's area kind KIND alone: hallway or zigzag), BASE+CASE (scene BASE on
a robot perturbed by one case of the task's evaluation.robustness, e.g. hardest+latency-period);
--suite runs the evaluation suite (suite_scenes), --robustness the robustness suite (every case on
the hardest and uniform scenes). Trials run in parallel, one episode
each, deterministic policy: the exported RUN_DIR/policy, those exported at milestone budgets too
(--milestones), or with --checkpoint [STEP] a training checkpoint (a killed run has no export yet).
Writes RUN_DIR/eval-<scene>[@<budget>].json (mean +- std of progress, success, COG deviation,
|pitch rate|, tip-overs, episode length) and one database row per trial.
Every trial's start is varied by the task's evaluation.trial_variation (position, yaw, joints), so
the trials are samples. `--baseline NAME --task TASK [RUN_DIR]` evaluates a baseline policy
(mjx_tracks.baselines: zero, full, random, scripted) the same way, recorded as a run of algorithm
`baseline` (default folder runs/baselines/TASK-NAME). `RUN_DIR RUN_DIR ...` evaluates several runs
in one process, the runs of one network whose tasks one program can take as data (a study's pack:
`train.run --seeds` / `--tasks`) in one vmapped rollout per scene program (at most
train.evaluation.EVAL_ENVS_PER_CALL environments a call, policies x trials; on the CPU one policy
after another), every run's reports and trial rows its own (the same trials as alone; floats
within the vmap's rounding). On stderr each scene says how long it took (its program's compilation
in the first scene of a program) and the seconds since the process started.
"""

from __future__ import annotations

import argparse
import datetime
import functools
import json
import os
import sys
import time

from mjx_tracks import atomic
from mjx_tracks.baselines import ALGO as BASELINE_ALGO, BASELINES, baseline
from mjx_tracks.envs.config import ConfigError, TaskConfig, apply_override, available_tasks, from_dict, load_config
from mjx_tracks.limits import MAX_SEED, MAX_TRIALS
from mjx_tracks.metrics import EPISODE, trial_row
from scenes.kinds import HARDEST, HELD_OUT, NAV, scene_kind
from train.evaluation import (EVAL_EPS, EVAL_SEED, EVAL_TRIALS, SCENES, fewer_trials_path, milestone_folder,
                              ROBUST, policies_runner, report_path, robustness_bases,
                              robustness_runner, robustness_scenes, saved_milestones, scene_config, suite_scenes,
                              trial_runner, trials_in)
from train.core.run_record import read_run_record, run_id_in, write_run_record

BASELINE_ROOT = os.path.join("runs", "baselines")  # where --baseline runs go unless RUN_DIR is given

def _policy(run_dir: str, checkpoint: str | None, milestone: int | None = None):
  """(make_act, params, step) of the exported policy, of the one exported at a milestone budget, or
  of a checkpoint ('latest' or a step number)."""
  from train.core.policy import act_from_params, load_checkpoint_params, load_policy_info, load_policy_params  # noqa: PLC0415
  if checkpoint is None:
    policy_dir = os.path.join(run_dir, "policy" if milestone is None else milestone_folder(milestone))
    spec, params = load_policy_params(policy_dir)
    return act_from_params(spec), params, load_policy_info(policy_dir).get("step")
  if checkpoint != "latest" and not checkpoint.isdigit():
    raise ValueError(f"--checkpoint takes a step number (or nothing, for the latest), got {checkpoint!r}")
  spec, params, step = load_checkpoint_params(run_dir, None if checkpoint == "latest" else int(checkpoint))
  return act_from_params(spec), params, step


def recorded_config(raw: dict, evaluation_sets=()) -> TaskConfig:
  """A run's recorded config, with `--set evaluation.KEY=VALUE` overrides of what it is evaluated on
  (e.g. held-out scenes added since it trained); any other key would change the task it learnt."""
  for item in evaluation_sets:
    if not item.startswith("evaluation."):
      raise ValueError(f"--set {item}: with a trained run only evaluation.* keys may change (its task is what it "
                       "trained on)")
  return from_dict(functools.reduce(apply_override, evaluation_sets, raw))


def _baseline_policy(name: str, cfg: TaskConfig):
  """(make_act, params, step) of a baseline: it sees the whole env state (trial_runner's observe)."""
  from mjx_tracks.envs.task_env import TrackedRobotEnv  # noqa: PLC0415
  act = baseline(name).make(TrackedRobotEnv(cfg))
  return (lambda _params: act), None, None


def _baseline_record(args) -> dict:
  """The run record of a baseline's folder: the one there, or a new one (and its database row)."""
  if args.task not in available_tasks():
    raise ValueError(f"--baseline needs --task, one of {', '.join(available_tasks())}; got {args.task!r}")
  cfg = load_config(args.task, tuple(args.set))
  b = baseline(args.baseline)
  if not b.applies(cfg):
    raise ValueError(f"baseline {b.name!r} ({b.meaning}) cannot drive {args.task}")
  args.run_dir = args.run_dir or os.path.join(BASELINE_ROOT, f"{args.task}-{b.name}")
  if run_id_in(args.run_dir):
    meta = read_run_record(args.run_dir)
    if (meta["algo"], meta.get("preset"), meta["task"]) != (BASELINE_ALGO, b.name, args.task):
      raise ValueError(f"{args.run_dir} holds {meta['task']} {meta['algo']} {meta.get('preset')}, not baseline "
                       f"{b.name} on {args.task}")
    if from_dict(meta["config"]) != cfg:
      raise ValueError(f"{args.run_dir} holds baseline {b.name} on {args.task} with other settings (--set); "
                       "give another folder")
    return meta
  import secrets  # noqa: PLC0415
  meta = {"run_id": f"{args.task}-{BASELINE_ALGO}-{b.name}-{secrets.token_hex(3)}", "task": args.task,
          "algo": BASELINE_ALGO, "preset": b.name, "seed": 0, "total_steps": 0, "config": cfg.to_dict()}
  write_run_record(args.run_dir, meta)
  from train.db import ExperimentDB, default_path  # noqa: PLC0415
  db = ExperimentDB(args.db or default_path(os.path.dirname(os.path.abspath(args.run_dir))))
  db.start(meta["run_id"], args.task, BASELINE_ALGO, b.name, 0, meta["config"], args.run_dir, 0)
  db.finish(meta["run_id"], "done", detail=b.meaning)
  return meta


def _record_trials(args: argparse.Namespace, run_dir: str, run_id: str, scene: str, budget: int | None,
                   per_trial: dict) -> None:
  """One database row per trial, where the run is in the database."""
  from train.db import ExperimentDB, default_path  # noqa: PLC0415
  db = ExperimentDB(args.db or default_path(os.path.dirname(os.path.abspath(run_dir))))
  try:
    db.run(run_id)
  except KeyError:
    print(f"note: run {run_id} is not in {db.path}; trials not recorded there", file=sys.stderr)
    return
  db.log_evals(run_id, [{"scene": scene, "budget": budget, "trial": i, **trial_row(per_trial, i)}
                        for i in range(args.trials)], replace=(scene, budget))


def parser() -> argparse.ArgumentParser:
  p = argparse.ArgumentParser(prog="python -m train.evaluate", description=__doc__.splitlines()[0])
  p.add_argument("run_dirs", nargs="*", metavar="RUN_DIR", help="a run folder (with --baseline: where the "
                 "baseline's records go); several: evaluated together, one program for the runs of one network "
                 "whose tasks may share one (a pack's: train.run --seeds / --tasks), each run's reports and "
                 "records its own")
  p.add_argument("--baseline", choices=tuple(BASELINES), help="evaluate a baseline policy on --task instead of "
                 "a trained one (mjx_tracks.baselines)")
  p.add_argument("--task", help="with --baseline: the task")
  p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                 help="with --baseline: a config override of the task (as train.run's); with a run: of its "
                 "evaluation.* keys (e.g. held-out scenes added since it trained)")
  p.add_argument("--trials", type=int, default=EVAL_TRIALS)
  p.add_argument("--scene", action="append", help=f"one of {', '.join(SCENES)}, {HELD_OUT}NAME "
                 f"(a fixed configuration of the task's evaluation section), {HARDEST}KIND (a terrain kind "
                 f"alone), {NAV}AREA (a navigation area alone) or BASE+CASE (a robustness case); default hardest; "
                 "repeat it for several (one process, each written to its own report); --suite lists a task's")
  p.add_argument("--suite", action="store_true", help="every scene of the task's evaluation suite "
                 "(hardest, uniform, each held-out staircase or terrain kind) instead of --scene")
  p.add_argument("--robustness", action="store_true", help="the robustness suite (evaluation.robustness): the "
                 "nominal robot and each perturbation alone, on the hardest (where the task has one) and uniform "
                 "scenes; with --suite, both")
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
  p.add_argument("--await-runs", action="store_true", help="started beside the training of the RUN_DIRs (a "
                 "study's pack, train.study.worker): wait for their first checkpoints, compile the evaluation's "
                 "programs for their network while they train, then evaluate the runs that stdin names (a "
                 "RUN_DIR a line) once it closes; none named: nothing evaluated (train.eval_ahead)")
  return p


def _policies(args, budgets: list[int | None], cfg: TaskConfig):
  """({budget: (make_act, params, step)}, observe): the baseline's (it may read the whole state) or
  the run's policy of each budget (it reads the observation)."""
  if args.baseline:
    return {None: _baseline_policy(args.baseline, cfg)}, (lambda s: s)
  return {b: _policy(args.run_dir, args.checkpoint, b) for b in budgets}, (lambda s: s.obs)


def stacked_params(params: list):
  """Policies' parameters (one network) stacked on a leading policy axis, as numpy arrays."""
  import jax  # noqa: PLC0415
  import numpy as np  # noqa: PLC0415
  return jax.tree_util.tree_map(lambda *x: np.stack(x), *params)


def slots_runner(args, scenes: list[str], own: list[TaskConfig], make_act):
  """train.evaluation.policies_runner for policies whose tasks are `own` (one a policy)."""
  return policies_runner(own[0], scenes, make_act, args.trials, args.eps, args.seed,
                         None if all(c == own[0] for c in own) else own)


def _evaluate_several(args, scenes: list[str], cfgs: list[TaskConfig], runs: list[tuple[str, dict]],
                      budgets: list[list[int | None]], run=None):
  """Each scene with the policy of each budget of every run (runs[i]: (folder, record), config
  cfgs[i]) in one vmapped rollout (train.evaluation.pack_trial_runner: one compilation per program
  of scene_programs; on the CPU one policy after another: vmapped_trials), every run's reports and
  trials its own; yields the summary lines. run: slots_runner's for these policies (runner_key's),
  built (and compiled) before, e.g. while the runs trained (train.eval_ahead)."""
  slots = pack_slots(list(range(len(runs))), budgets)  # one policy each
  t0 = time.monotonic()
  loaded = [_policy(runs[i][0], None, b) for i, b in slots]  # (make_act, params, step): one network (_several)
  _took(f"restored {len(slots)} policies", t0)
  params = stacked_params([p for _, p, _ in loaded])
  ready = run is not None
  if not ready:
    run = slots_runner(args, scenes, [cfgs[i] for i, _ in slots], loaded[0][0])
  from train import evaluation  # noqa: PLC0415  (its vmapped_trials, as policies_runner reads it)
  per_call = evaluation.policies_per_call(len(slots), args.trials)
  if not evaluation.vmapped_trials():
    how = "one after another (on the CPU)"
  elif per_call < len(slots):
    how = f"in one program, {per_call} a call ({evaluation.EVAL_ENVS_PER_CALL:,} environments at most)"
  else:
    how = "in one program"
  for scene in scenes:
    print(f"{scene}: running {args.trials} trials of up to {scene_config(cfgs[0], scene).episode.max_steps} steps "
          f"for {len(slots)} policies of {len(runs)} runs {how}, "
          f"{'its program compiled ahead' if ready else 'compiling first where no scene before it shares its program'}"
          " ...", file=sys.stderr, flush=True)
    t0 = time.monotonic()
    for (i, budget), (_, _, step), per_trial in zip(slots, loaded, run(params, scene)):
      folder, meta = runs[i]
      out = _write_report(args, folder, meta, scene, budget, step, per_trial)
      yield _summary(meta["task"], scene, budget, args.trials, per_trial, out)
    _took(f"{scene}: done", t0)


def _took(what: str, t0: float) -> None:
  """'WHAT in S s (T s since the process started)' on stderr: where an evaluation's time goes (the
  first scene of a program includes its compilation; the time since the start, the imports too)."""
  age = _process_age()
  since = "" if age is None else f" ({age:.0f} s since the process started)"
  print(f"{what} in {time.monotonic() - t0:.1f} s{since}", file=sys.stderr, flush=True)


def _process_age() -> float | None:
  """Seconds since this process started (Linux's /proc: field 22 of its stat is its start in clock
  ticks after boot), or None where that cannot be read."""
  try:
    with open("/proc/self/stat") as f:
      start_ticks = int(f.read().rsplit(")", 1)[1].split()[19])  # the fields after the name start at field 3
    with open("/proc/uptime") as f:
      return float(f.read().split()[0]) - start_ticks / os.sysconf("SC_CLK_TCK")
  except (OSError, ValueError, IndexError):
    return None


def pack_slots(group: list[int], budgets: list[list[int | None]]) -> list[tuple[int, int | None]]:
  """A group's policies: (run index, budget) of each budget of each of its runs, in order."""
  return [(i, b) for i in group for b in budgets[i]]


def runner_key(folders: list[str], slots: list[tuple[int, int | None]], scenes: list[str], network: str) -> tuple:
  """What a runner of _evaluate_several is built for: its policies (pack_slots' of runs in folders,
  as (folder, budget)), scenes and network (network_key): runners of equal keys are one."""
  return tuple((folders[i], b) for i, b in slots), tuple(scenes), network


def network_key(network: dict) -> str:
  """A policy's network (its spec's JSON) as a key: runs of equal keys share evaluation programs."""
  return json.dumps(network, sort_keys=True)


def _network(run_dir: str) -> str:
  from train.core.policy import load_policy_info  # noqa: PLC0415
  return network_key(load_policy_info(os.path.join(run_dir, "policy"))["network"])


def _evaluate(args, meta: dict, scenes: list[str], budgets: list[int | None], cfg0: TaskConfig):
  """Runs each scene with the policy of each budget (one compilation per program of
  scene_programs: one for every scene of a stair task); writes each report and its trials; yields
  the summary lines."""
  policies, observe = _policies(args, budgets, cfg0)
  run = trial_runner(cfg0, scenes, policies[budgets[0]][0], args.trials, args.eps, args.seed, bool(args.video), observe)
  for scene in scenes:
    steps = scene_config(cfg0, scene).episode.max_steps  # a held-out area may be longer than the task's
    print(f"{scene}: running {args.trials} trials of up to {steps} steps ({len(budgets)} "
          f"polic{'y' if len(budgets) == 1 else 'ies'}; compiling first where no scene before it shares its "
          "program: a minute or more the first time on this machine) ...", file=sys.stderr, flush=True)
    t0 = time.monotonic()
    for budget, (_, params, policy_step) in policies.items():
      per_trial, qpos, render_model = run(params, scene)
      out = _write_report(args, args.run_dir, meta, scene, budget, policy_step, per_trial)
      if args.video:
        from mjx_tracks.tools.render import camera_for, render_frames, write_video  # noqa: PLC0415
        shown = qpos[:int(per_trial["length"][0]) + 1]  # the reset, then trial 0 until its episode ended
        frames = render_frames(render_model, shown, **camera_for(scene_kind(cfg0.scene.kind).camera))
        write_video(args.video, frames, fps=1 / cfg0.control.period)
      yield _summary(meta["task"], scene, budget, args.trials, per_trial, out)
    _took(f"{scene}: done", t0)


def _evaluate_robustness(args, meta: dict, bases: list[str], budgets: list[int | None], cfg0: TaskConfig):
  """Every robustness case on each scene of `bases` with the policy of each budget, the cases of a
  base in one batch, the bases in one compilation where they share a program (robustness_runner);
  writes each case's report (scene BASE+CASE) and its trials; yields the summary lines."""
  policies, observe = _policies(args, budgets, cfg0)
  cases = [c.name for c in cfg0.evaluation.robustness]
  run = robustness_runner(cfg0, bases, policies[budgets[0]][0], args.trials, args.eps, args.seed, observe)
  for base in bases:
    print(f"{base}: running {len(cases)} robustness cases x {args.trials} trials in one batch ...",
          file=sys.stderr, flush=True)
    t0 = time.monotonic()
    for budget, (_, params, policy_step) in policies.items():
      for case, per_trial in run(params, base).items():
        scene = f"{base}{ROBUST}{case}"
        out = _write_report(args, args.run_dir, meta, scene, budget, policy_step, per_trial)
        yield _summary(meta["task"], scene, budget, args.trials, per_trial, out)
    _took(f"{base}: done", t0)


def _write_report(args, run_dir: str, meta: dict, scene: str, budget: int | None, policy_step,
                  per_trial: dict) -> str:
  """RUN_DIR/eval-<scene>[@<budget>].json (or --out) and the database's trial rows; returns the path.
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
  out = args.out or report_path(run_dir, scene, budget)
  fuller = None if args.out else trials_in(out)
  if fuller is not None and fuller > args.trials:
    out = fewer_trials_path(out, args.trials)
    print(f"note: kept {report_path(run_dir, scene, budget)} ({fuller} trials) and its database rows; "
          f"this {args.trials}-trial result goes to {out} only", file=sys.stderr)
  atomic.write_json(out, report)
  if fuller is None or fuller <= args.trials:
    _record_trials(args, run_dir, meta["run_id"], scene, budget, per_trial)
  return out


def _summary(task: str, scene: str, budget: int | None, trials: int, per_trial: dict, out: str) -> str:
  """One line: each figure's mean (+- std where it is not a rate) with its unit (mjx_tracks.metrics)."""
  at = "" if budget is None else f" @ {budget:,} steps"
  figures = []
  for m in EPISODE:
    v = per_trial[m.name]
    sd = "" if m.aggregate == "rate" else f" +- {v.std():.3g}"
    figures.append(f"{m.name.replace('_', ' ')} {v.mean():.3g}{sd}{' ' + m.unit if m.unit else ''}")
  return f"{task} {scene}{at}: {trials} trials, {', '.join(figures)} -> {out}"


def _jobs(args, cfg: TaskConfig, run_dir: str | None) -> tuple[list[str], list[str], list[int | None]]:
  """(scenes, base scenes of the robustness suite: every case on each in one batch, milestone
  budgets with None for the final policy) to evaluate; ValueError on bad input."""
  if args.scene is not None and (args.suite or args.robustness):
    raise ValueError("--scene names scenes; --suite and --robustness name theirs: give one of them")
  named = list(dict.fromkeys(args.scene or ["hardest"]))  # each once, in order
  scenes = suite_scenes(cfg) if args.suite else [] if args.robustness else named
  for scene in scenes + (robustness_scenes(cfg) if args.robustness else []):
    scene_config(cfg, scene)  # ConfigError on an unknown scene
  if args.robustness and (args.out or args.video):
    raise ValueError("--out and --video take one scene; --robustness writes a report per case")
  bases = robustness_bases(cfg) if args.robustness else []
  budgets: list[int | None] = [None]
  if args.baseline and (args.milestones or args.checkpoint is not None):
    raise ValueError("a baseline has no milestones nor checkpoints")
  if args.milestones:
    if args.checkpoint is not None:
      raise ValueError("--milestones evaluates exported policies; drop --checkpoint")
    budgets = [*saved_milestones(run_dir), None]
  if len(scenes) * len(budgets) > 1 and (args.out or args.video):
    raise ValueError("--out and --video take one scene and one policy")
  return scenes, bases, budgets


def main(argv: list[str] | None = None) -> int:
  args = parser().parse_args(argv)
  args.argv = sys.argv[1:] if argv is None else argv
  if not 1 <= args.trials <= MAX_TRIALS or not 0.0 <= args.eps <= 1.0 or not 0 <= args.seed <= MAX_SEED:
    print(f"error: --trials must be from 1 to {MAX_TRIALS:,}, --eps in [0, 1], --seed from 0 to {MAX_SEED}",
          file=sys.stderr)
    return 2
  if args.await_runs:  # beside a training that holds most of the GPU's memory: take it as needed (before JAX starts)
    os.environ.setdefault("XLA_PYTHON_CLIENT_PREALLOCATE", "false")
  from mjx_tracks import compile_cache  # noqa: PLC0415
  compile_cache.enable()
  try:
    lines = _one(args) if len(args.run_dirs) <= 1 and not args.await_runs else _several(args)
    for line in lines:
      print(line, flush=True)
  except (ConfigError, FileNotFoundError, ValueError) as e:
    print(f"error: {e}", file=sys.stderr)
    return 2
  except KeyboardInterrupt:  # Ctrl-C: no traceback; each report file is written whole (atomic) or not at all
    print("interrupted: the scenes reported above are written; the others are not", file=sys.stderr)
    return 130
  return 0


def _one(args):
  """The summary lines of one run's (or a baseline's) evaluation."""
  args.run_dir = args.run_dirs[0] if args.run_dirs else None
  if args.baseline:
    meta = _baseline_record(args)
  elif args.run_dir is None or args.task:
    raise ValueError("give a RUN_DIR to evaluate a trained run (its config is recorded), or --baseline NAME "
                     "--task TASK [--set KEY=VALUE ...]")
  else:
    meta = read_run_record(args.run_dir)
  cfg = recorded_config(meta["config"], () if args.baseline else args.set)
  scenes, bases, budgets = _jobs(args, cfg, args.run_dir)
  yield from _evaluate(args, meta, scenes, budgets, cfg) if scenes else ()
  yield from _evaluate_robustness(args, meta, bases, budgets, cfg) if bases else ()


def _several(args):
  """The summary lines of several runs' evaluations: the scenes of runs that may share a program in
  one (_evaluate_several, in groups: mjx_tracks.envs.task_data.packing_conflict), the robustness
  suite run by run."""
  if args.baseline or args.task or args.out or args.video or args.checkpoint is not None:
    raise ValueError("--await-runs evaluates the exported policies of runs that end: drop --baseline, --task, "
                     "--out, --video and --checkpoint" if args.await_runs else
                     "--baseline, --task, --out, --video and --checkpoint take one RUN_DIR")
  if args.await_runs and not args.run_dirs:
    raise ValueError("--await-runs needs the RUN_DIRs of the runs it waits for")
  folders, compiled = list(dict.fromkeys(args.run_dirs)), {}
  if args.await_runs:
    from train.eval_ahead import compile_ahead, named_runs  # noqa: PLC0415
    compiled = compile_ahead(args, folders, sys.stdin)
    folders = named_runs(sys.stdin, folders)
  runs = [(d, read_run_record(d)) for d in folders]
  cfgs = [recorded_config(meta["config"], args.set) for _, meta in runs]
  jobs = [_jobs(args, cfg, d) for cfg, (d, _) in zip(cfgs, runs)]
  networks = [_network(d) for d, _ in runs]
  for g in pack_groups(cfgs, [scenes for scenes, _, _ in jobs], networks):
    if jobs[g[0]][0]:
      key = runner_key(folders, pack_slots(g, [budgets for _, _, budgets in jobs]), jobs[g[0]][0], networks[g[0]])
      yield from _evaluate_several(args, jobs[g[0]][0], [cfgs[i] for i in g], [runs[i] for i in g],
                                   [jobs[i][2] for i in g], compiled.get(key))
  for (d, meta), cfg, (_, bases, budgets) in zip(runs, cfgs, jobs):
    if bases:
      yield from _evaluate_robustness(argparse.Namespace(**{**vars(args), "run_dir": d}), meta, bases, budgets, cfg)


def pack_groups(cfgs: list[TaskConfig], scenes: list[list[str]], networks: list[str]) -> list[list[int]]:
  """The runs (their tasks, scenes, network_key) in groups whose evaluations one program takes:
  tasks that differ in data only (mjx_tracks.envs.task_data.packing_conflict), the same scenes, one
  network; each group's indices in order."""
  from mjx_tracks.envs.task_data import packing_conflict  # noqa: PLC0415
  groups: list[list[int]] = []
  for i, cfg in enumerate(cfgs):
    fits = (g for g in groups if packing_conflict(cfg, cfgs[g[0]]) is None and scenes[i] == scenes[g[0]]
            and networks[i] == networks[g[0]])
    group = next(fits, None)
    if group is None:
      groups.append([i])
    else:
      group.append(i)
  return groups


if __name__ == "__main__":
  sys.exit(main())

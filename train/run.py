"""`python -m train.run --task TASK`: train a policy with PPO or SAC (built from Brax's parts).

    python -m train.run --task asc-inc-cog                      # preset by backend: cpu | gpu
    python -m train.run --task des-inc-ang --algo sac --preset paper
    python -m train.run --task asc-inc-cog --set reward.cog_scale=0.5 --steps 5000000 --out runs/a
    python -m train.run --resume runs/a                         # continue an interrupted or killed run
    python -m train.run --resume runs/a --steps 8000000         # train a finished run further
    python -m train.run --task des-inc-ang --hp discounting=0.995  # a preset's hyper-parameter
    python -m train.run --task asc-inc-cog --library brax       # Brax's own ppo.train (no checkpoints)
    python -m train.run --task nav --seeds 0,1,2,3,4 --out runs/nav  # 5 runs in one program: runs/nav/s0 ...
    python -m train.run --tasks asc-inc-cog,des-inc-ang --seeds 0,1 --out runs/p  # 4 runs: runs/p/asc-inc-cog/s0 ...
    python -m train.run --task asc-inc-cog --algo sac --preset paper --seeds 0,1 --early-stops return,none --out runs/e
                                                                # 4 runs: runs/e/stop-return/s0 ... runs/e/stop-none/s1

Writes into the run directory: run.json, checkpoints/ (orbax, the whole training state, every
--checkpoint-every seconds and at the end), policy/ (the exported policy), tb/ (TensorBoard);
statistics, events and the run's status go to the experiment database. Ctrl-C or SIGTERM stops
after the current update with a checkpoint and the policy (exit 130 / 143); a second Ctrl-C quits
at once. Several GPUs are used as one device mesh; see the README for several processes. With
--library brax, Brax's train() runs instead: run.json, the database's run row and events, and
policy/ are written; no checkpoints or statistics rows, and a stop ends the run with nothing to resume.
"""

from __future__ import annotations

import argparse
import os
import sys

from mjx_tracks.envs.config import ConfigError
from train.core.ahead import CHOICES as AHEAD_CHOICES, DEFAULT as AHEAD_DEFAULT
from train.core.algos.ppo_split import CHOICES as SPLIT_CHOICES, DEFAULT as SPLIT_DEFAULT
from train.core.checkpoints import CHECKPOINT_EVERY_S, KEEP
from train.db import ExperimentDB, default_path
from train.core.early_stop import EARLY_STOP_SUCCESS, EARLY_STOP_TIMES, criterion_name
from train.core.presets import SB3
from train.core.run_record import seed_folder
from train.core.plan import DEFAULT_LIBRARY, LIBRARIES, RESUMABLE, RunError, RunPlan, new_run_id, plan_run, write_run_json  # noqa: F401  (new_run_id: API)

STATUS = {"done": "done", "early_stop": "stopped_early", "interrupted": "interrupted"}  # loop's reason -> db status


def parser() -> argparse.ArgumentParser:
  p = argparse.ArgumentParser(prog="python -m train.run", description=__doc__.splitlines()[0],
                              formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
  p.add_argument("--task", help="task name (configs/TASK.yaml)")
  p.add_argument("--algo", choices=("ppo", "sac", "td3"), help="default ppo (with --library sb3: sac); td3 with --library sb3 only")
  p.add_argument("--preset", help="cpu | gpu (| paper for sac; every algorithm with --library sb3); default from the "
                                  "JAX backend (with --library sb3: paper)")
  p.add_argument("--num-envs", type=int, help="parallel environments, a multiple of the device count "
                                                "(default: the preset's)")
  p.add_argument("--steps", type=int, help="total environment steps (default: the preset's)")
  p.add_argument("--seed", type=int, help="default 0")
  p.add_argument("--seeds", metavar="S,S,...",
                 help="several runs that differ only in their seed, trained as one vmapped program on one "
                      "device, each a run of its own (folder OUT/s<seed>, records, early stop, --resume)")
  p.add_argument("--tasks", metavar="T,T,...",
                 help="instead of --task, with --seeds: each task with each seed, all in one program, where the "
                      "tasks differ only in what it takes as data (stair direction, sampler, reward kind: "
                      "mjx_tracks/envs/task_data.py), each run in OUT/<task>/s<seed>")
  p.add_argument("--out", help="run directory (default runs/<run id>)")
  p.add_argument("--db", help="experiment database (default: experiments.sqlite beside the run directory)")
  p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                 help="dotted config override, e.g. --set reward.cog_scale=0.5")
  p.add_argument("--library", choices=tuple(LIBRARIES), metavar="LIBRARY",
                 help="whose training loop: " + "; ".join(f"{k}: {v}" for k, v in LIBRARIES.items())
                      + f" (default {DEFAULT_LIBRARY})")
  p.add_argument("--hp", action="append", default=[], metavar="KEY=VALUE",
                 help="a hyper-parameter of the preset, e.g. --hp discounting=0.995 (train/core/presets.py names them)")
  p.add_argument("--resume", metavar="DIR", help="continue the run in DIR from its last readable checkpoint")
  p.add_argument("--early-stop", nargs="?", const="return", metavar="CRITERION",
                 help="stop at a criterion: 'return' (alone: the mean return of recent training episodes "
                      "reaches the paper's 0.5 ascent / 0.6 descent), 'success' (the hardest-staircase "
                      f"probe's success reaches {EARLY_STOP_SUCCESS} in {EARLY_STOP_TIMES['success']} probes "
                      "in a row), or either with =THRESHOLD[xN] (N reports in a row); 'none': train every "
                      "step (default: the preset's: PPO gpu stops at 'success' on tasks with a hardest scene)")
  p.add_argument("--early-stops", metavar="CRITERION,CRITERION",
                 help="instead of --early-stop, with --seeds: each criterion (as --early-stop takes it, 'none' "
                      "included) with each task and seed, all in one program, each run in "
                      "OUT/stop-<criterion>/[<task>/]s<seed>")
  p.add_argument("--probe-every", type=int, metavar="STEPS",
                 help="steps between evaluations on the hardest staircase (the trials of train.evaluate "
                      "--scene hardest); 0: none (default: the preset's, stair tasks only)")
  p.add_argument("--milestones", metavar="STEPS,STEPS",
                 help="step budgets at which the policy is also exported, to RUN/milestones/<budget>/ "
                      "(at the first update at or past each), e.g. 250000,500000; train.evaluate --milestone")
  p.add_argument("--checkpoint-every", type=float, default=CHECKPOINT_EVERY_S, metavar="SECONDS",
                 help=f"wall time between checkpoints (default {CHECKPOINT_EVERY_S:g} s)")
  p.add_argument("--keep-checkpoints", type=int, default=KEEP, metavar="K",
                 help=f"checkpoints kept (default {KEEP})")
  p.add_argument("--compile-ahead", choices=AHEAD_CHOICES, default=AHEAD_DEFAULT,
                 help="compile the in-training evaluations' programs in threads of their own, started once "
                      "the training step is lowered: they compile beside it and while the run trains (auto: "
                      "where JAX's backend is not the CPU; train.core.ahead)")
  p.add_argument("--split-update", choices=SPLIT_CHOICES, default=SPLIT_DEFAULT,
                 help="PPO: the training step as programs that compile side by side (the policy and the "
                      "physics; the rest of the env step; the SGD), its env steps a loop on the host; a run of "
                      "one task on one device only (auto: where JAX's backend is not the CPU; "
                      "train.core.algos.ppo_split)")
  p.add_argument("--coordinator", metavar="HOST:PORT",
                 help="one process of a multi-process run (jax.distributed): process 0's address")
  p.add_argument("--num-processes", type=int, help="with --coordinator: how many processes")
  p.add_argument("--process-id", type=int, help="with --coordinator: this process's index, 0 ... N-1")
  return p


def _start_records(plan: RunPlan, db_path: str | None):
  """run.json and the database rows; under jax.distributed only process 0 keeps records."""
  import jax  # noqa: PLC0415
  if jax.process_index() != 0:
    from train.db import NullDB  # noqa: PLC0415
    return NullDB()
  write_run_json(plan)
  db = ExperimentDB(db_path or default_path(os.path.dirname(plan.out_dir)))
  db.start(plan.run_id, plan.task, plan.algo, plan.preset_name, plan.seed, plan.cfg.to_dict(),
           plan.out_dir, plan.total_steps, resume_step=plan.start_step if plan.resume else None)
  return db


def _train(plan: RunPlan, args) -> int:
  """Prepares the run (a resume restores its checkpoint before any record is touched), starts its
  records, trains, and closes them; returns the exit code."""
  if plan.library not in RESUMABLE:
    return _train_elsewhere(plan, args)
  from train.core.interrupts import StopRequest  # noqa: PLC0415
  with StopRequest() as stop:
    try:
      plan, session = (_sb3_session if plan.library == SB3 else _own_session)(plan, args, stop)
    except RunError as e:
      print(f"error: {e}", file=sys.stderr)
      return 2
    db = _start_records(plan, args.db)
    status, final = "crashed", {}
    try:
      final = session(db)
      status = STATUS[final["reason"]]
    finally:
      db.finish(plan.run_id, status, final, final.get("step"), _detail(status, stop, plan))
  if status == "interrupted":
    print(f"interrupted at step {final['step']:,}: checkpoint and policy saved; continue with: "
          f"python -m train.run --resume {plan.out_dir}", file=sys.stderr, flush=True)
    return stop.exit_code
  print(finished_lines(plan, final, getattr(db, "path", None)), flush=True)
  return 0


def group_plans(args) -> list[RunPlan]:
  """One plan per task of --tasks (or --task) and seed of --seeds (each folder OUT/s<seed>, with
  --tasks OUT/<task>/s<seed>; without --out, runs/<its run id>)."""
  bad = [flag for flag, given in (("--seed", args.seed is not None), ("--resume", args.resume),
                                  ("--coordinator", args.coordinator),
                                  ("--library " + str(args.library), args.library not in (None, DEFAULT_LIBRARY)))
         if given]
  if bad:
    raise RunError(f"--seeds does not go with {', '.join(bad)} (resume each run alone: --resume OUT/[<task>/]s<seed>)")
  try:
    seeds = [int(x) for x in args.seeds.split(",")]
  except ValueError:
    raise RunError(f"--seeds takes whole numbers separated by commas, e.g. 0,1,2; got {args.seeds!r}") from None
  tasks, stops = _tasks(args), _early_stops(args)
  if len(set(seeds)) != len(seeds) or len(seeds) * len(tasks) * len(stops) < 2:
    raise RunError(f"--seeds needs at least two different seeds (or --tasks two tasks, or --early-stops two "
                   f"criteria); got {args.seeds!r}")
  plans = [plan_run(argparse.Namespace(**{**vars(args), "task": task, "tasks": None, "seed": s, "seeds": None,
                                          "early_stop": stop, "early_stops": None,
                                          "out": _run_folder(args, task, s, stop)}))
           for stop in stops for task in tasks for s in seeds]
  for task in tasks:  # runs of two spellings of one criterion would share their tags and results
    named = [criterion_name(p.early_stop) for p in plans if p.task == task and p.seed == seeds[0]]
    if len(set(named)) < len(named):
      raise RunError(f"--early-stops {args.early_stops}: on {task} two of them are one criterion ({', '.join(named)})")
  return plans


def _tasks(args) -> list[str]:
  """The tasks of a program: --tasks T,T,... (different ones, not with --task) or --task."""
  if args.tasks is None:
    return [args.task]
  tasks = [x.strip() for x in args.tasks.split(",")]
  if args.task or not all(tasks) or len(set(tasks)) != len(tasks):
    raise RunError(f"--tasks takes different task names separated by commas, instead of --task; got {args.tasks!r}")
  return tasks


def _early_stops(args) -> list[str | None]:
  """The early stops of a program's runs: --early-stops C,C,... (different ones, not with --early-stop),
  or --early-stop's (None: the preset's)."""
  if args.early_stops is None:
    return [args.early_stop]
  stops = args.early_stops.split(",")  # as written: each names its runs' folder
  if args.early_stop is not None or not all(stops) or len(set(stops)) != len(stops):
    raise RunError(f"--early-stops takes different criteria separated by commas, instead of --early-stop; "
                   f"got {args.early_stops!r}")
  return stops


def _run_folder(args, task: str, seed: int, stop: str | None) -> str | None:
  """A run's folder in a program: OUT/s<seed>, with --tasks OUT/<task>/s<seed>, with --early-stops
  OUT/stop-<criterion>/ in front; None without --out."""
  if not args.out:
    return None
  return seed_folder(args.out, seed, task if args.tasks else None, stop if args.early_stops else None)


def _train_group(plans: list[RunPlan], args) -> int:
  """The runs of --seeds in one program (train.core.group): each run's records as a run's own."""
  from train.core.group import prepare_group, run_tags, train_group  # noqa: PLC0415
  from train.core.interrupts import StopRequest  # noqa: PLC0415
  from train.core.session import SessionOptions, device_summary  # noqa: PLC0415
  p = plans[0]
  print(f"{len(plans)} runs ({', '.join(q.run_id for q in plans)}): {p.algo} ({p.preset_name} preset), "
        f"{p.num_envs} envs each, in one program on {device_summary()}, {p.total_steps:,} steps each", flush=True)
  with StopRequest() as stop:
    try:
      t = prepare_group(plans)
    except RunError as e:
      print(f"error: {e}", file=sys.stderr)
      return 2
    dbs = [_start_records(q, args.db) for q in plans]
    ended: dict[int, str] = {}  # run index -> its status, recorded as soon as it ended

    def on_end(i: int, final: dict) -> None:
      ended[i] = STATUS[final["reason"]]
      dbs[i].finish(plans[i].run_id, ended[i], final, final.get("step"), _detail(ended[i], stop, plans[i]))

    try:
      finals = train_group(t, plans, dbs, stop, SessionOptions(args.checkpoint_every, args.keep_checkpoints,
                                                                args.compile_ahead, args.split_update), on_end)
    finally:
      for i, (q, db) in enumerate(zip(plans, dbs)):
        if i not in ended:  # the program failed before this run ended
          db.finish(q.run_id, "crashed", {}, None, _detail("crashed", stop, q))
    statuses = [ended[i] for i in range(len(plans))]
  for q, final, tag in zip(plans, finals, run_tags(plans)):
    print(f"{tag}: {final['step']:,} steps, {STATUS[final['reason']]} -> {q.out_dir}", flush=True)
  if "interrupted" in statuses:
    print("interrupted: checkpoints and policies saved; continue each run alone with:\n"
          + "\n".join(f"  python -m train.run --resume {q.out_dir}" for q in plans), file=sys.stderr, flush=True)
    return stop.exit_code
  return 0


def _own_session(plan: RunPlan, args, stop):
  """(plan, train(db) -> final) of this project's trainer, its state built or restored."""
  from train.core.session import SessionOptions, device_summary, prepare, train  # noqa: PLC0415
  early = f", early stop at {plan.early_stop}" if plan.early_stop else ""
  print(f"run {plan.run_id}: {plan.algo} ({plan.preset_name} preset), {plan.num_envs} envs on "
        f"{device_summary()}, {plan.total_steps:,} steps{early} -> {plan.out_dir}", flush=True)
  options = SessionOptions(args.checkpoint_every, args.keep_checkpoints, args.compile_ahead, args.split_update)
  prepared = prepare(plan, options)
  return prepared.t.plan, lambda db: train(prepared, db, stop, options)


def _sb3_session(plan: RunPlan, args, stop):
  """(plan, train(db) -> final) of Stable-Baselines3 (train.core.sb3_trainer)."""
  from train.extras import require_extra  # noqa: PLC0415
  require_extra("sb3", "--library sb3")
  from train.core import sb3_trainer  # noqa: PLC0415
  print(f"run {plan.run_id}: {plan.algo} ({plan.preset_name} preset) by Stable-Baselines3, {plan.num_envs} envs, "
        f"{plan.total_steps:,} steps -> {plan.out_dir}", flush=True)
  plan, learn = sb3_trainer.prepare(plan, args.keep_checkpoints)
  return plan, lambda db: learn(db, stop, args.checkpoint_every)


def _train_elsewhere(plan: RunPlan, args) -> int:
  """A run another library trains (train.core.brax_reference): recorded like ours, but with nothing
  to resume from if it is stopped."""
  import signal  # noqa: PLC0415

  from train.core import brax_reference  # noqa: PLC0415

  def stop(signum, _frame):  # SIGTERM as Ctrl-C: Brax's loop cannot be asked to stop between updates
    raise KeyboardInterrupt(signum)

  previous = signal.signal(signal.SIGTERM, stop)
  print(f"run {plan.run_id}: {plan.algo} ({plan.preset_name} preset) by {plan.library}, {plan.num_envs} envs, "
        f"{plan.total_steps:,} steps -> {plan.out_dir}", flush=True)
  db = _start_records(plan, args.db)
  status, final = "crashed", {}
  try:
    final = brax_reference.train_run(plan)
    status = "done"
  except KeyboardInterrupt as e:
    status = "interrupted"
    print(f"interrupted: --library {plan.library} saves no checkpoints; nothing to resume", file=sys.stderr)
    return 128 + (e.args[0] if e.args else signal.SIGINT)
  finally:
    signal.signal(signal.SIGTERM, previous)
    db.finish(plan.run_id, status, final, final.get("step"), "" if status == "done" else status)
  print(finished_lines(plan, final, getattr(db, "path", None)), flush=True)
  return 0


def finished_lines(plan: RunPlan, final: dict, db_path: str | None) -> str:
  """What a finished run made and the three commands a user runs next."""
  out = plan.out_dir
  figures = ", ".join(f"{name} {final[key]:.2f}" for key, name in (
      ("return_mean", "return"), ("progress_mean", "progress"), ("success_rate", "success"),
      ("tipped_rate", "tip-overs")) if isinstance(final.get(key), (int, float)))
  why = {"done": "", "early_stop": f" (early stop: {plan.early_stop})"}.get(final["reason"], "")
  return "\n".join([
      f"done{why}: {final['step']:,} steps in {final.get('wall_s', 0):,.0f} s"
      + (f"; last training episodes: {figures}" if figures else ""),  # --library brax reports none
      f"made: {out}/ with policy/ (the exported policy), "
      + ("checkpoints/, run.json, tb/ (TensorBoard)" if plan.library in RESUMABLE else "run.json")
      + (f"; records in {db_path}" if db_path else ""),
      "next:",
      f"  python -m train.evaluate {out} --scene hardest --trials 10   # the policy on the task's hardest scene",
      f"  python -m train.server --runs {os.path.dirname(out)}   # the dashboard (the [server] extra), http://127.0.0.1:8000",
      f"  python -c \"from train.core.policy import load_policy; act = load_policy('{out}/policy')\"   # act(obs) in Python"])


def _detail(status: str, stop, plan: RunPlan) -> str:
  if status == "stopped_early":
    return f"early stop: {plan.early_stop}"
  if status == "interrupted" and stop.requested is not None:
    import signal  # noqa: PLC0415
    return signal.Signals(stop.requested).name
  return ""


def main(argv: list[str] | None = None) -> int:
  args = parser().parse_args(argv)
  if args.checkpoint_every < 0 or args.keep_checkpoints < 1:
    print("error: --checkpoint-every must be >= 0 and --keep-checkpoints >= 1", file=sys.stderr)
    return 2
  from mjx_tracks import compile_cache  # noqa: PLC0415
  compile_cache.enable()
  if args.coordinator:
    if args.num_processes is None or args.process_id is None:
      print("error: --coordinator needs --num-processes and --process-id", file=sys.stderr)
      return 2
    import jax  # noqa: PLC0415
    jax.config.update("jax_cpu_collectives_implementation", "gloo")  # CPU processes talk over gloo
    jax.distributed.initialize(args.coordinator, args.num_processes, args.process_id)
  try:
    try:
      for flag, given in (("--tasks", args.tasks), ("--early-stops", args.early_stops)):
        if given is not None and args.seeds is None:
          raise RunError(f"{flag} needs --seeds (e.g. --seeds 0)")
      plans = group_plans(args) if args.seeds is not None else [plan_run(args)]
    except (RunError, ConfigError) as e:
      print(f"error: {e}", file=sys.stderr)
      return 2
    return _train(plans[0], args) if args.seeds is None else _train_group(plans, args)
  finally:
    if args.coordinator:  # all processes leave together: no "WatchTasks failed" lines from a late one
      import jax  # noqa: PLC0415
      jax.distributed.shutdown()


def _main(argv: list[str] | None = None) -> int:
  """main, with a Ctrl-C before the run starts reported in one line."""
  try:
    return main(argv)
  except KeyboardInterrupt:
    print("interrupted before training started; nothing to resume", file=sys.stderr)
    return 130


if __name__ == "__main__":
  sys.exit(_main())

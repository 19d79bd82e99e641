"""`python -m train.evaluate RUN RUN ... --await-runs`: a study pack's final evaluation started beside
its training (train.study.worker.run_pack), so that its programs compile while the runs train.

It waits until every run folder has its record and a checkpoint (or its exported policy), compiles
the evaluation's programs for the runs' network with those parameters (one program per group of
train.evaluate.pack_groups, for every policy at once: train.evaluation.pack_trial_runner's
compile_for; with --milestones, the policies of the budgets each run's record plans too), then reads
the folders to evaluate from stdin, a line each, until it closes: the runs that ended. Those
groups' evaluations then call the programs compiled here (JAX's caches serve a call the program
`jit(f).lower(args).compile()` made for arguments of the same shapes); a group that differs (a run
that did not end, one that stopped before a milestone) compiles its own, as without this.

Started after the training instead, the paper study's 40-run SAC pack spent ~60 s of its ~67 s
after training in a new evaluation process on one H200: 5 s of imports, 6.5 s restoring the
policies with the process's first device work, 31 s tracing and compiling its one program, 16 s
running the five scenes (results/speed/profile/final-evaluation-40-sac-runs-H200-2026-11-29.json).
Where stdin speaks before the checkpoints are there (a training that failed early) or before the
compilation starts, nothing is compiled ahead; nor where compiling fails (said in one line): it is
only a head start. The robustness suite's programs are not compiled ahead."""

from __future__ import annotations

import os
import select
import sys
import time

POLL_S = 2.0  # s between looks at the run folders while waiting for their first checkpoints
READ_TRIES = 5  # a checkpoint read that fails (the training's clean-up removed it meanwhile) is tried again


def compile_ahead(args, folders: list[str], stream) -> dict:
  """{train.evaluate.runner_key: its runner (train.evaluate.slots_runner), compiled} for the groups
  train.evaluate._several will evaluate, once every folder has a checkpoint; {} where `stream`
  (stdin) speaks first, or where compiling ahead fails (the evaluation then compiles as without it)."""
  if not _wait_for_checkpoints(folders, stream) or _readable(stream):
    print("the runs to evaluate were named before their programs could compile: nothing compiled ahead",
          file=sys.stderr, flush=True)
    return {}
  try:
    return _compile_groups(args, folders)
  except Exception as e:  # noqa: BLE001  (XLA, orbax and JAX raise many types; the evaluation goes on without it)
    print(f"warning: compiling ahead failed ({type(e).__name__}: {str(e).strip()[:200]}); the evaluation "
          "compiles after the training", file=sys.stderr, flush=True)
    return {}


def _compile_groups(args, folders: list[str]) -> dict:
  """compile_ahead's runners, the runs' latest parameters standing in for their policies."""
  from train.core.policy import act_from_params  # noqa: PLC0415
  from train.core.run_record import read_run_record  # noqa: PLC0415
  from train.evaluate import (_jobs, _took, network_key, pack_groups, pack_slots, recorded_config,  # noqa: PLC0415
                              runner_key, slots_runner, stacked_params)
  from train.evaluation import scene_programs  # noqa: PLC0415
  t0 = time.monotonic()
  records = [read_run_record(d) for d in folders]
  cfgs = [recorded_config(meta["config"], args.set) for meta in records]
  scenes = [_jobs(args, cfg, d)[0] for cfg, d in zip(cfgs, folders)]
  # each run's policies: those of the budgets its record plans (--milestones), then its final one
  budgets = [[*(sorted(meta.get("milestones") or []) if args.milestones else []), None] for meta in records]
  loaded = [_latest_params(d) for d in folders]  # (network spec, parameters)
  networks = [network_key(spec.to_json()) for spec, _ in loaded]
  compiled = {}
  for g in pack_groups(cfgs, scenes, networks):
    if not scenes[g[0]]:
      continue
    slots = pack_slots(g, budgets)  # one policy each, the latest parameters standing in
    run = slots_runner(args, scenes[g[0]], [cfgs[i] for i, _ in slots], act_from_params(loaded[g[0]][0]))
    params = stacked_params([loaded[i][1] for i, _ in slots])
    for _, draws in scene_programs(cfgs[g[0]], scenes[g[0]]):
      run.compile_for(params, next(iter(draws)))  # one scene of each program
    compiled[runner_key(folders, slots, scenes[g[0]], networks[g[0]])] = run
  _took(f"compiled the evaluation of {len(folders)} runs ahead ({len(compiled)} group(s))", t0)
  return compiled


def named_runs(stream, folders: list[str]) -> list[str]:
  """The folders that `stream` names (a line each, until it closes), in the order of `folders`;
  ValueError on a name that is not one of them."""
  names = {os.path.abspath(line.strip()) for line in stream if line.strip()}
  unknown = names - {os.path.abspath(d) for d in folders}
  if unknown:
    raise ValueError(f"--await-runs: stdin named {sorted(unknown)[0]}, which is not one of the RUN_DIRs")
  chosen = [d for d in folders if os.path.abspath(d) in names]
  print(f"evaluating {len(chosen)} of {len(folders)} runs (those named on stdin)", file=sys.stderr, flush=True)
  return chosen


def _wait_for_checkpoints(folders: list[str], stream) -> bool:
  """True once every folder has its record and a checkpoint or its exported policy; False where
  `stream` has something to read (or has closed) first."""
  said = False
  while not all(_has_parameters(d) for d in folders):
    if _readable(stream) is not False:
      return False
    if not said:
      print(f"waiting for the first checkpoints of {len(folders)} runs ...", file=sys.stderr, flush=True)
      said = True
    time.sleep(POLL_S)
  return True


def _has_parameters(folder: str) -> bool:
  from train.core.checkpoints import saved_steps  # noqa: PLC0415
  from train.core.run_record import run_id_in  # noqa: PLC0415
  exported = os.path.exists(os.path.join(folder, "policy", "policy.json"))
  return run_id_in(folder) is not None and (exported or bool(saved_steps(folder)))


def _latest_params(folder: str):
  """(network spec, parameters) of the run's exported policy, else of its latest checkpoint; a read
  that fails is tried again (the training's clean-up may have removed that checkpoint meanwhile)."""
  from train.core.policy import load_checkpoint_params, load_policy_params  # noqa: PLC0415

  def read():
    if os.path.exists(os.path.join(folder, "policy", "policy.json")):
      return load_policy_params(os.path.join(folder, "policy"))
    return load_checkpoint_params(folder)[:2]
  for _ in range(READ_TRIES - 1):
    try:
      return read()
    except (OSError, ValueError):
      time.sleep(POLL_S)
  return read()


def _readable(stream) -> bool | None:
  """Whether reading `stream` would not wait (a line, or its end); None for a stream without a file
  descriptor (e.g. a test's io.StringIO), which never waits but has not been written to meanwhile:
  the waiting for checkpoints ends at it, the compilation goes ahead."""
  try:
    fd = stream.fileno()
  except (AttributeError, OSError):  # io.UnsupportedOperation is an OSError
    return None
  return bool(select.select([fd], [], [], 0)[0])

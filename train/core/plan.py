"""Planning a run: task, preset, config, run directory and id from the command line, or from a
run directory's run.json for --resume. Bad requests raise RunError before anything is written."""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import os
import secrets
from typing import Any

from mjx_tracks.envs.config import TaskConfig, from_dict, load_config
from mjx_tracks.limits import MAX_ENVS, MAX_SEED, MAX_STEPS
from train.core.early_stop import NO_EARLY_STOP, EarlyStop, parse_early_stop
from train.core.presets import CPU_DEFAULT, SB3, get_preset, with_hyperparams
from train.core.run_record import read_run_record, run_id_in, write_run_record


class RunError(Exception):
  """A bad request: reported as one line, nothing written."""


# whose training loop trains a run (train.run --library); every run is recorded alike
LIBRARIES = {
    "mjx-tracks": "this project's trainer (train/core): checkpoints, resume, probes, early stop, milestones",
    "brax": "Brax's own ppo.train / sac.train on the same env and preset: no checkpoints, resume, probes, "
            "early stop or milestones (the parity reference)",
    SB3: "Stable-Baselines3's SAC / TD3 / PPO (the [sb3] extra) on the task's Gymnasium VectorEnv, with its own "
           "presets (train/core/sb3_presets.py): checkpoints, resume and the return early stop; no probes or milestones",
}
DEFAULT_LIBRARY = "mjx-tracks"
RESUMABLE = (DEFAULT_LIBRARY, SB3)  # libraries whose runs save checkpoints


@dataclasses.dataclass(frozen=True)
class RunPlan:
  run_id: str
  out_dir: str
  task: str
  algo: str
  preset_name: str
  preset: Any
  seed: int
  overrides: tuple[str, ...]
  cfg: TaskConfig
  total_steps: int
  num_envs: int
  resume: bool
  early_stop: EarlyStop | None
  probe_every: int  # steps between hardest-staircase probes (0: none)
  start_step: int = 0  # the checkpoint a resumed run continues from
  milestones: tuple[int, ...] = ()  # step budgets at which the policy is exported to RUN/milestones/<budget>
  hp: tuple[str, ...] = ()  # --hp KEY=VALUE: the preset's fields the run changed (already in preset)
  library: str = DEFAULT_LIBRARY  # LIBRARIES


def default_preset(algo: str, library: str = DEFAULT_LIBRARY) -> str:
  """The preset a run gets without --preset: gpu on an accelerator; on the CPU, the preset that
  solves the flagship task within 10 minutes on 2 cores (ppo) or the small one (sac); with
  --library sb3, its paper preset (one robot)."""
  import jax  # noqa: PLC0415
  if library == SB3:
    return "paper"
  if jax.default_backend() in ("gpu", "cuda", "rocm", "tpu"):
    return "gpu"
  return CPU_DEFAULT.get(algo, "cpu")


# options a resumed run takes from its run.json; giving one with --resume is refused
RESUME_FIXED = ("task", "algo", "preset", "num_envs", "seed", "set", "hp", "library", "out", "early_stop",
                "probe_every", "milestones")
# options a resumed run may be given anew
RESUME_FREE = ("steps", "db", "checkpoint_every", "keep_checkpoints", "compile_ahead", "split_update")


def _flag(name: str) -> str:
  return f"--{name.replace('_', '-')}"


def _plan_resume(args: argparse.Namespace) -> RunPlan:
  """The plan of a run to continue; refuses options that would change it, and finished runs."""
  given = [_flag(n) for n in RESUME_FIXED if getattr(args, n) not in (None, [], False)]
  if given:
    free = [_flag(n) for n in RESUME_FREE]
    raise RunError(f"--resume continues a run with its own settings; drop {', '.join(given)} "
                   f"(only {', '.join(free[:-1])} and {free[-1]} may be given)")
  try:
    meta = read_run_record(args.resume)
  except (FileNotFoundError, ValueError) as e:
    raise RunError(f"--resume {args.resume}: {e}") from None
  library = meta.get("library", DEFAULT_LIBRARY)
  if library not in RESUMABLE:
    raise RunError(f"run {meta['run_id']} was trained by --library {library}, which saves no checkpoints: "
                   "nothing to resume; train it again")
  total = meta["total_steps"] if args.steps is None else args.steps
  if not 1 <= total <= MAX_STEPS:
    raise RunError(f"--steps must be from 1 to {MAX_STEPS:,}")
  from train.core.checkpoints import checkpoint_dir, saved_steps, trained_to  # noqa: PLC0415  (orbax: only when resuming)
  steps = saved_steps(args.resume)
  if not steps:
    raise RunError(f"--resume {args.resume}: no checkpoint in {checkpoint_dir(args.resume)} to resume from")
  done = steps[-1]
  if trained_to(args.resume, total):
    raise RunError(f"run {meta['run_id']} is finished ({done:,} of {meta['total_steps']:,} steps); to train "
                   f"it further: --resume {args.resume} --steps N with N > {done:,}")
  hp = tuple(meta.get("hp") or ())  # runs from before --hp recorded none
  try:
    preset = with_hyperparams(get_preset(meta["algo"], meta["preset"], library), hp)
  except ValueError as e:
    raise RunError(f"--resume {args.resume}: its run.json's {e}") from None
  preset = dataclasses.replace(preset, num_envs=meta["num_envs"])
  _check_devices(meta["num_envs"])
  cfg = from_dict(meta["config"])
  return RunPlan(meta["run_id"], os.path.abspath(args.resume), meta["task"], meta["algo"], meta["preset"],
                 preset, meta["seed"], tuple(meta["overrides"]), cfg, total, meta["num_envs"], True,
                 _early_stop_of(meta, cfg), meta.get("probe_every", 0), done,
                 tuple(meta.get("milestones") or ()), hp, library)


def _early_stop_of(meta: dict, cfg) -> EarlyStop | None:
  """A run.json's early stop (runs from before `early_stop` recorded `early_stop_return`)."""
  if meta.get("early_stop"):
    return parse_early_stop(meta["early_stop"], cfg)
  old = meta.get("early_stop_return")
  return None if old is None else EarlyStop("return", old)


def _check_devices(num_envs: int) -> None:
  """The environments must split evenly over all devices (of all processes)."""
  import jax  # noqa: PLC0415
  n = jax.device_count()
  if num_envs % n:
    raise RunError(f"--num-envs {num_envs} is not a multiple of the {n} devices; "
                   f"use e.g. {max(n, num_envs // n * n):,}")


def new_run_id(task: str, algo: str, seed: int) -> str:
  """TASK-ALGO-sSEED-TIME-XXXXXX: the random suffix keeps runs started in the same second apart;
  under jax.distributed every process takes process 0's."""
  stamp = datetime.datetime.now().strftime("%Y%m%d-%H%M%S")
  return _shared(f"{task}-{algo}-s{seed}-{stamp}-{secrets.token_hex(3)}")


def _primary() -> bool:
  import jax  # noqa: PLC0415
  return jax.process_index() == 0


def _shared(text: str, size: int = 256) -> str:
  """Process 0's value of a short string, on every process."""
  import jax  # noqa: PLC0415
  if jax.process_count() == 1:
    return text
  import numpy as np  # noqa: PLC0415
  from jax.experimental import multihost_utils  # noqa: PLC0415
  data = np.frombuffer(text.encode().ljust(size, b" "), np.uint8)
  return bytes(np.asarray(multihost_utils.broadcast_one_to_all(data))).decode().strip()


def plan_run(args: argparse.Namespace) -> RunPlan:
  """Resolves task, preset, config and run directory; raises RunError / ConfigError on bad input."""
  if args.resume:
    return _plan_resume(args)
  if not args.task:
    raise RunError("--task is required (or --resume DIR)")
  library = getattr(args, "library", None) or DEFAULT_LIBRARY
  if library not in LIBRARIES:
    raise RunError(f"--library {library!r}: one of {', '.join(LIBRARIES)}")
  algo, seed = args.algo or ("sac" if library == SB3 else "ppo"), 0 if args.seed is None else args.seed
  preset_name = args.preset or default_preset(algo, library)
  try:
    preset = with_hyperparams(get_preset(algo, preset_name, library), args.hp)
  except ValueError as e:
    raise RunError(str(e))
  overrides = tuple(preset.config_overrides) + tuple(args.set)
  cfg = load_config(args.task, overrides)
  num_envs = preset.num_envs if args.num_envs is None else args.num_envs
  if not 1 <= num_envs <= MAX_ENVS:
    raise RunError(f"--num-envs must be from 1 to {MAX_ENVS:,}")
  _check_devices(num_envs)
  steps = preset.num_timesteps if args.steps is None else args.steps
  if not 1 <= steps <= MAX_STEPS:
    raise RunError(f"--steps must be from 1 to {MAX_STEPS:,}")
  if not 0 <= seed <= MAX_SEED:
    raise RunError(f"--seed must be from 0 to {MAX_SEED}")
  run_id = new_run_id(args.task, algo, seed)
  out_dir = os.path.abspath(args.out or os.path.join("runs", run_id))
  if _primary() and os.path.exists(out_dir) and os.listdir(out_dir):  # process 0 may have begun it
    other = run_id_in(out_dir)
    what = f"run {other}" if other else "other files"
    raise RunError(f"{out_dir} already holds {what}; use --resume {out_dir} or another --out")
  try:
    early = _early_stop(args.early_stop, preset, cfg)
  except ValueError as e:
    raise RunError(str(e))
  if library != DEFAULT_LIBRARY:
    early, probe_every, milestones = _library_limits(library, args, early)
  else:
    probe_every = probe_every_of(args.probe_every, early, preset, cfg)
    milestones = parse_milestones(getattr(args, "milestones", None), steps)
  return RunPlan(run_id, out_dir, args.task, algo, preset_name, preset, seed, tuple(args.set),
                 cfg, steps, num_envs, False, early, probe_every, milestones=milestones, hp=tuple(args.hp),
                 library=library)


def _library_limits(library: str, args: argparse.Namespace, early: EarlyStop | None):
  """(early stop, probe interval, milestones) of a run another library trains: none of them but the
  paper's return criterion with sb3 (its reports carry the training return; it has no probe);
  asking for another is refused (the preset's own early stop is dropped)."""
  from train.core.checkpoints import CHECKPOINT_EVERY_S, KEEP  # noqa: PLC0415  (orbax: only for these runs)
  given = [f"--{n.replace('_', '-')}" for n in ("probe_every", "milestones", "coordinator")
           if getattr(args, n, None) not in (None, 0, "")]
  keeps_early = library == SB3 and early is not None and not early.needs_probe
  if args.early_stop not in (None, NO_EARLY_STOP) and not keeps_early:
    given.append("--early-stop" + (" success (sb3 has no probe; return[=X] it has)" if library == SB3 else ""))
  given += [f"--{n.replace('_', '-')}" for n, default in (("checkpoint_every", CHECKPOINT_EVERY_S), ("keep_checkpoints", KEEP))
            if getattr(args, n, default) != default and library not in RESUMABLE]  # it saves none
  if given:
    raise RunError(f"--library {library} trains with {LIBRARIES[library]}; drop {', '.join(given)}")
  return (early if keeps_early and args.early_stop is not None else None), 0, ()


def parse_milestones(text: str | None, total: int) -> tuple[int, ...]:
  """'250000,500000' -> (250000, 500000): distinct step budgets in [1, total), ascending."""
  if not text:
    return ()
  try:
    budgets = sorted({int(x) for x in text.split(",") if x.strip()})
  except ValueError:
    raise RunError(f"--milestones takes step counts separated by commas, e.g. 250000,500000; got {text!r}")
  if not budgets or budgets[0] < 1 or budgets[-1] >= total:
    raise RunError(f"--milestones must lie in [1, {total:,}) (the run's --steps); got {text!r}")
  return tuple(budgets)


def _early_stop(given: str | None, preset, cfg) -> EarlyStop | None:
  """The criterion given, else the preset's (PPO gpu: success on the probe scene, for tasks that
  have one); None for 'none'."""
  if given == NO_EARLY_STOP:
    return None
  if given is None:
    given = preset.early_stop if preset.early_stop and cfg.scene.probe_scene else None
  return parse_early_stop(given, cfg) if given else None


def probe_interval(preset_steps: int, cfg: TaskConfig) -> int:
  """A preset's probe interval (steps) for the task: the presets' are for the default episode length
  (configs/defaults.yaml, the stair tasks' 50 control steps); a probe's trials run its episodes' full
  length, so the interval grows with it in whole multiples (80-step terrain episodes: 2x; nav's 240: 5x).
  Probing nav every 81,920 steps cost 8x the training in a 5-run study on one H100 (2026-11-25)."""
  from mjx_tracks.envs.config import default_config  # noqa: PLC0415
  return preset_steps * max(1, -(-cfg.episode.max_steps // default_config().episode.max_steps))


def probe_every_of(given: int | None, early: EarlyStop | None, preset, cfg) -> int:
  """Steps between probes of the task's probe scene (SceneKind.probe_scene): as given, else the preset's
  (tasks with a probe scene; probe_interval); an early stop on success needs them."""
  if given is not None and given < 0:
    raise RunError("--probe-every must be >= 0 (0: no probe)")
  if given == 0 and early is not None and early.needs_probe:
    raise RunError(f"--early-stop {early} needs the probe; drop --probe-every 0")
  every = given if given is not None else (probe_interval(preset.probe_steps, cfg) if cfg.scene.probe_scene else 0)
  if early is not None and early.needs_probe and every == 0:
    every = probe_interval(preset.probe_steps, cfg) or preset.training_metrics_steps
  if every and not cfg.scene.probe_scene:
    raise RunError(f"--probe-every: task {cfg.task} has no probe scene")
  return every


def write_run_json(plan: RunPlan) -> None:
  """run.json (atomically); a resumed run keeps its creation time."""
  now = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
  meta = {"run_id": plan.run_id, "task": plan.task, "algo": plan.algo, "preset": plan.preset_name,
          "seed": plan.seed, "overrides": list(plan.overrides), "hp": list(plan.hp), "library": plan.library, "config": plan.cfg.to_dict(),
          "total_steps": plan.total_steps, "num_envs": plan.num_envs,
          "early_stop": str(plan.early_stop) if plan.early_stop else None, "probe_every": plan.probe_every,
          "milestones": list(plan.milestones),
          "created": read_run_record(plan.out_dir).get("created", now) if plan.resume else now}
  write_run_record(plan.out_dir, meta)

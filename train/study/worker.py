"""What runs on a Dask worker: one attempt at a study cell, in a scratch folder of the worker's own:
train (or resume from the run folder sent along), evaluate, and send the run folder back: moved
into the study's folder where the worker shares its filesystem (Handoff), else as a tar (another
machine)."""

from __future__ import annotations

import dataclasses
import errno
import fcntl
import io
import json
import os
import shutil
import socket
import subprocess
import sys
import tarfile
import tempfile
import uuid

from mjx_tracks import atomic
from train.core.run_record import run_id_in
from train.db import FINISHED, ExperimentDB

# what a worker runs, after its own Python (sys.executable there: workers may be other machines)
TRAIN = ("-m", "train.run")
EVALUATE = ("-m", "train.evaluate")
RUN_DB = "run.sqlite"  # each run's records travel inside its folder
EVALUATE_LOG = "evaluate.log"  # a pack's evaluation's output in its scratch folder, early or not (one log)


def pack(folder: str) -> bytes:
  """The folder as a gzipped tar, at gzip's fastest level: a run folder is mostly checkpoints of
  float arrays, which level 9 (the default) packs hardly smaller at twice the time (a 15 MB array:
  7.50 MB in 0.46 s, level 1 7.55 MB in 0.22 s, on the 2-core machine); a 60-run study's folders
  (1.9 GB) took 30-70 s to come back at level 9."""
  buf = io.BytesIO()
  with tarfile.open(fileobj=buf, mode="w:gz", compresslevel=1) as tar:
    tar.add(folder, arcname=".")
  return buf.getvalue()


def unpack(data: bytes, folder: str) -> None:
  os.makedirs(folder, exist_ok=True)
  with tarfile.open(fileobj=io.BytesIO(data), mode="r:gz") as tar:
    tar.extractall(folder, filter="data")


HANDOFF = ".handoff"  # STUDY/.handoff: a folder per study process (its token's), where run folders are moved in


@dataclasses.dataclass(frozen=True)
class Handoff:
  """STUDY/.handoff/<token>, where a worker that shares the study's filesystem moves a run folder
  instead of sending it back as a tar: no gzip, no copy through Dask, no whole pack of checkpoints in
  memory (the paper study's 20 PPO runs, ~2 GB of checkpoints, took 55-63 s to come back as tars on
  one host: results/speed/group/paper-packed-2-H200-2026-11-28b.md). A worker shares it where it
  reads the study process's token there; a worker on another machine does not, and sends tars."""
  folder: str  # holds TOKEN and the folders moved in, each under a name of its own until the study takes it
  token: str

  TOKEN = "token"

  @staticmethod
  def create(study_folder: str):
    """(a new handoff folder with a token of its own, its token file held locked for as long as the
    caller keeps it open); the folders of earlier study processes are removed, unless one still
    holds its own (two processes on one study folder never remove each other's)."""
    root = os.path.abspath(os.path.join(study_folder, HANDOFF))  # workers' working folders differ
    os.makedirs(root, exist_ok=True)
    for name in os.listdir(root):
      _remove_unless_held(os.path.join(root, name))
    token = uuid.uuid4().hex
    handoff = Handoff(os.path.join(root, token), token)
    os.makedirs(handoff.folder)
    lock = open(os.path.join(handoff.folder, Handoff.TOKEN), "w")  # half written: a worker sends a tar
    fcntl.flock(lock, fcntl.LOCK_EX)
    lock.write(handoff.token)
    lock.flush()
    return handoff, lock

  def shared(self) -> bool:
    """Whether this process sees the study's folder (its token there)."""
    try:
      with open(os.path.join(self.folder, Handoff.TOKEN)) as f:
        return f.read() == self.token
    except OSError:
      return False

  def take(self, folder: str) -> str:
    """Moves the folder into the handoff folder; its new path (a rename where both are on one
    filesystem, else a copy; an error, not a folder made anew, where the handoff folder is gone)."""
    moved = os.path.join(self.folder, uuid.uuid4().hex)
    try:
      os.rename(folder, moved)
    except OSError as e:
      if e.errno != errno.EXDEV:
        raise
      shutil.move(folder, moved)
    return moved


def _remove_unless_held(folder: str) -> None:
  """Removes an earlier study process's handoff folder (the folders its workers moved in after it
  ended) unless that process still holds its token; one without a token yet is left."""
  try:
    lock = open(os.path.join(folder, Handoff.TOKEN))
  except OSError:
    return
  with lock:
    try:
      fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
      return  # another study process on this folder, running
    shutil.rmtree(folder, ignore_errors=True)


def receive(res: dict, folder: str) -> str | None:
  """Puts an attempt's run folder (res: run_cell's result or a pack's cell's) at `folder`, replacing
  what was there only once it is in place beside it: moved from the handoff folder ("moved"), or
  unpacked from its tar ("tar"); None where none came back (or the moved one is gone)."""
  moved = res.get("moved")
  if (moved and not os.path.isdir(moved)) or (not moved and res.get("tar") is None):
    return None
  incoming = folder + ".incoming"
  shutil.rmtree(incoming, ignore_errors=True)
  if moved:
    shutil.move(moved, incoming)
  else:
    unpack(res["tar"], incoming)
  shutil.rmtree(folder, ignore_errors=True)
  os.rename(incoming, folder)
  return "moved" if moved else "tar"


def pid_file(out: str) -> str:
  """Where a run in place names the process of its current phase: OUT.pid (beside OUT.log)."""
  return out + ".pid"


def read_pid_file(out: str) -> dict | None:
  """{"pid", "host", "phase"} of the process now working on the run in `out`, if one is recorded."""
  try:
    with open(pid_file(out)) as f:
      return json.load(f)
  except (OSError, ValueError):
    return None


def _call(argv: list[str], log_path: str, pid_path: str | None = None, phase: str = "") -> int:
  """Runs argv, output to log_path; with pid_path, names the process there while it runs."""
  with open(log_path, "a") as log:
    proc = subprocess.Popen(argv, stdout=log, stderr=subprocess.STDOUT, env=os.environ.copy())
    if pid_path:
      atomic.write_json(pid_path, {"pid": proc.pid, "host": socket.gethostname(), "phase": phase}, indent=None)
    try:
      return proc.wait()
    finally:
      if pid_path and os.path.exists(pid_path):
        os.remove(pid_path)


def _train_then_evaluate(run_args: list[str], eval_args: list[str], out: str, db: str, resume: bool, train: bool,
                         commands: tuple[tuple[str, ...], tuple[str, ...]], log: str,
                         pid_path: str | None = None) -> tuple[str, int]:
  """Trains into `out` (resuming it if asked; not at all if not train), then, if that went well and
  there are evaluation arguments, evaluates; (phase reached, its exit code). With pid_path, each
  phase's process is named there while it runs (so a stop reaches the evaluation too)."""
  phase, rc = "train", 0
  if train:
    given = ["--resume", out] if resume else [*run_args, "--out", out]
    rc = _call([sys.executable, *commands[0], *given, "--db", db], log, pid_path, "train")
  if rc == 0 and eval_args:
    phase, rc = "evaluate", _call(_evaluate_argv(commands[1], out, eval_args, db), log, pid_path, "evaluate")
  return phase, rc


def _evaluate_argv(command: tuple[str, ...], run: str, eval_args: list[str], db: str) -> list[str]:
  """The evaluation of the run in folder `run`, its records to `db`."""
  return [sys.executable, *command, run, *eval_args, "--db", db]


def run_cell(run_args: list[str], eval_args: list[str], resume: bytes | None, train: bool = True,
             commands: tuple[tuple[str, ...], tuple[str, ...]] = (TRAIN, EVALUATE), handoff: Handoff | None = None) -> dict:
  """{"rc", "phase" (train | evaluate), "tar" (the run folder, or None), "moved" (where the run folder
  was moved instead, handoff shared), "log_tail", "worker"}."""
  scratch = tempfile.mkdtemp(prefix="study-cell-")
  out, log = os.path.join(scratch, "run"), os.path.join(scratch, "attempt.log")
  try:
    if resume is not None:
      unpack(resume, out)
    phase, rc = _train_then_evaluate(run_args, eval_args, out, os.path.join(out, RUN_DB), resume is not None,
                                     train, commands, log)
    return _outcome(out, rc, phase, open(log).read() if os.path.exists(log) else "", handoff)
  finally:
    shutil.rmtree(scratch, ignore_errors=True)


def run_pack(pack_args: list[str], members: list[str], eval_args: list[str],
             commands: tuple[tuple[str, ...], tuple[str, ...]] = (TRAIN, EVALUATE), handoff: Handoff | None = None,
             early: bool | None = None) -> dict:
  """First attempts of cells that differ only in their seed (and task, early stop:
  train.study.spec.packs_of), as one program (`train.run --seeds [--tasks] [--early-stops]`);
  members: each run's folder in the program's output (train.study.spec.pack_folders); then the
  runs that ended (their total steps or their early stop; also where the program failed later, e.g.
  by another run) are evaluated together, in one process (_evaluate_together). early: that process
  starts beside the training and compiles its programs meanwhile (EarlyEvaluation; default: where
  this worker's JAX is not kept to the CPU, early_evaluation_here). Returns {"cells": {member:
  run_cell's result}}: each run's folder comes back with its own records (run.sqlite) and the
  pack's training and evaluation output."""
  scratch = tempfile.mkdtemp(prefix="study-pack-")
  out, shared_db, log = (os.path.join(scratch, name) for name in ("pack", "pack.sqlite", "train.log"))
  folders, beside = {m: os.path.join(out, m) for m in members}, None
  try:
    if eval_args and (early_evaluation_here() if early is None else early):
      beside = EarlyEvaluation(list(folders.values()), eval_args, commands[1], shared_db, scratch)
    rc = _call([sys.executable, *commands[0], *pack_args, "--out", out, "--db", shared_db], log, None, "train")
    ended = {m: folders[m] for m in members if _ended(folders[m], shared_db)}
    evaluated = beside.finish(ended) if beside is not None else None
    if evaluated is None:  # none beside the training, or it had stopped before it was told the runs
      evaluated = _evaluate_together(ended, eval_args, commands[1], shared_db, scratch) if eval_args and ended \
          else {m: ("train", 0, "") for m in ended}
    for m in members:  # each run's rows (training and evaluation) in a database of its own, as a single run's
      if os.path.isdir(folders[m]) and os.path.exists(shared_db):
        ExperimentDB(os.path.join(folders[m], RUN_DB)).import_runs(shared_db, only=[run_id_in(folders[m])])
    trained, results = open(log).read() if os.path.exists(log) else "", {}
    for m in members:  # a run that did not end failed with the program (its checkpoints, if any, come back)
      phase, code, output = evaluated.get(m, ("train", rc or 1, ""))
      results[m] = _outcome(folders[m], code, phase, trained + output, handoff)
    return {"cells": results}
  finally:
    if beside is not None:
      beside.stop()
    shutil.rmtree(scratch, ignore_errors=True)


def early_evaluation_here() -> bool:
  """Whether a pack's evaluation starts beside its training on this worker: where its JAX may use
  an accelerator (JAX_PLATFORMS is not `cpu`). On a CPU worker its compilation would take cores
  from the training (a study's CPU slots run one-thread runs side by side): a CPU-only worker of
  another cluster (train.study --scheduler) should set JAX_PLATFORMS=cpu, as the local one does."""
  return os.environ.get("JAX_PLATFORMS", "").strip().lower() != "cpu"


class EarlyEvaluation:
  """A pack's evaluation started beside its training (`train.evaluate RUN ... --await-runs`,
  train.eval_ahead): it compiles its programs while the runs train, and evaluates the runs that
  `finish` names once the training has ended (what that saves: train.eval_ahead)."""

  def __init__(self, folders: list[str], eval_args: list[str], command: tuple[str, ...], db: str, scratch: str):
    self.log = os.path.join(scratch, EVALUATE_LOG)
    with open(self.log, "a") as out:
      self.proc = subprocess.Popen([sys.executable, *command, *folders, *eval_args, "--db", db, "--await-runs"],
                                   stdin=subprocess.PIPE, stdout=out, stderr=subprocess.STDOUT, text=True,
                                   env=os.environ.copy())

  def finish(self, ended: dict[str, str]) -> dict[str, tuple[str, int, str]] | None:
    """{member: ("evaluate", the process's exit code, its output)} of the `ended` runs ({member:
    folder}), once the process has evaluated them; {} where none ended (the process is stopped);
    None where the process had stopped before (e.g. it failed while compiling): the caller
    evaluates them in a new one."""
    if not ended or self.proc.poll() is not None:
      self.stop()
      return {} if not ended else None
    try:
      self.proc.stdin.write("".join(f"{folder}\n" for folder in ended.values()))
      self.proc.stdin.close()
    except OSError:  # it stopped meanwhile (a broken pipe)
      self.stop()
      return None
    rc = self.proc.wait()
    with open(self.log) as f:
      output = f.read()
    return {m: ("evaluate", rc, output) for m in ended}

  def stop(self) -> None:
    """Ends the process if it still runs (the pack's training failed, or the attempt is cut off)."""
    if self.proc.poll() is None:
      self.proc.terminate()
      try:
        self.proc.wait(timeout=30)
      except subprocess.TimeoutExpired:
        self.proc.kill()
        self.proc.wait()
    if self.proc.stdin and not self.proc.stdin.closed:
      try:
        self.proc.stdin.close()
      except OSError:
        pass


def _ended(folder: str, db: str) -> bool:
  """Whether the run in `folder` ended (its record in the pack's database says so)."""
  run_id = run_id_in(folder)
  if run_id is None or not os.path.exists(db):
    return False
  try:
    return ExperimentDB(db).run(run_id)["status"] in FINISHED  # its total steps, or its early stop
  except KeyError:
    return False


def _evaluate_together(folders: dict[str, str], eval_args: list[str], command: tuple[str, ...], db: str,
                       scratch: str) -> dict[str, tuple[str, int, str]]:
  """Evaluates the run folders in one process (`train.evaluate RUN RUN ...`: one program for the
  runs that may share one), their trials recorded in the pack's database `db`; {member:
  ("evaluate", the process's exit code, its output)}. One process per run, side by side, took 500 s
  for a 40-run pack on one H200 (results/speed/group/paper-packed-2-H200-2026-11-28.md)."""
  log = os.path.join(scratch, EVALUATE_LOG)
  rc = _call([sys.executable, *command, *folders.values(), *eval_args, "--db", db], log)
  output = open(log).read() if os.path.exists(log) else ""
  return {m: ("evaluate", rc, output) for m in folders}


def _outcome(folder: str, rc: int, phase: str, output: str, handoff: Handoff | None = None) -> dict:
  """An attempt's result: {"rc", "phase", "tar" (the run folder, or None), "moved" (the run folder's
  path in the study's handoff folder, where this worker shares it, instead of a tar), "log_tail",
  "worker"}; the output is appended to the folder's study-attempts.log (every attempt's, in order)."""
  res = {"rc": rc, "phase": phase, "tar": None, "log_tail": output[-2000:], "worker": _worker_name()}
  if not os.path.isdir(folder):
    return res
  with open(os.path.join(folder, "study-attempts.log"), "a") as f:
    f.write(output)
  if handoff is not None and handoff.shared():
    return {**res, "moved": handoff.take(folder)}
  return {**res, "tar": pack(folder)}


def run_in_place(run_args: list[str], eval_args: list[str], out: str, db: str, resume: bool, train: bool = True,
                 commands: tuple[tuple[str, ...], tuple[str, ...]] = (TRAIN, EVALUATE)) -> dict:
  """One run on a worker that shares the filesystem (the server's machine): trains into `out`
  (resuming it if asked; not at all if not train) with its records in `db`, then evaluates;
  {"rc", "phase", "log_tail", "worker"}."""
  log = out + ".log"  # beside the run folder (train.run wants a new folder empty): every attempt's output
  phase, rc = _train_then_evaluate(run_args, eval_args, out, db, resume, train, commands, log, pid_file(out))
  return {"rc": rc, "phase": phase, "log_tail": open(log).read()[-2000:] if os.path.exists(log) else "",
          "worker": _worker_name()}


def _worker_name() -> str:
  try:
    from distributed import get_worker  # noqa: PLC0415
    return str(get_worker().name)
  except (ImportError, ValueError):
    return "local"

"""Running a study on a Dask cluster: every unfinished cell is submitted as one task
(`train.study.worker.run_cell`); run folders come back into STUDY/runs/ (moved there by a worker
that shares the study's filesystem, else as tars: train.study.worker.Handoff) and their records
into STUDY/study.sqlite; failed attempts are retried from the last run folder that came back, up
to the study's `retries`; every cell's state and attempts live in STUDY/state.json, so a study
started again skips finished cells."""

from __future__ import annotations

import dataclasses
import json
import os
import shutil
import signal
import sys
import threading
import time

from mjx_tracks import atomic
from train.db import ExperimentDB
from train.core.plan import DEFAULT_LIBRARY
from train.core.run_record import read_run_record, run_id_in
from train.study.spec import Cell, StudySpec, cells, pack_folders, pack_train_args, packs_of
from train.study.worker import EVALUATE, RUN_DB, TRAIN, Handoff, pack, receive, run_cell, run_pack

STUDY_DB = "study.sqlite"  # every run's records, merged from the run folders that come back
STATE = "state.json"  # every cell's status and attempts
STOP_WAIT_S = 300.0  # how long a stopped study waits for its runs to save a checkpoint and come back


def cell_folder_of(study_folder: str, cell_id: str) -> str:
  """Where a run's folder comes back to: STUDY/runs/<id with / as _>."""
  return os.path.join(study_folder, "runs", cell_id.replace("/", "_"))


def cell_folder(study_folder: str, cell: Cell) -> str:
  return cell_folder_of(study_folder, cell.id)


def _trained_to_the_end(run_folder: str) -> bool:
  """Whether the run's newest checkpoint is at its total steps (train.run refuses to resume it)."""
  from train.core.checkpoints import trained_to  # noqa: PLC0415  (JAX: only where a run came back)
  try:
    total = read_run_record(run_folder, ()).get("total_steps")
  except (FileNotFoundError, ValueError):
    total = None
  return trained_to(run_folder, total)


def next_attempt(cell: Cell, run_folder: str, ended: list[dict]) -> tuple[bool, bool]:
  """(whether the attempt starts from the run folder, whether it trains) after the ended attempts.
  This project's runs resume from their checkpoints and only evaluate once trained to the end; a
  run another library trains (no checkpoints) is evaluated again only if its training finished
  (its policy written and an evaluation begun), else trained again from the start."""
  evaluated = bool(ended) and ended[-1]["phase"] == "evaluate"  # training finished (or stopped early)
  if cell.library != DEFAULT_LIBRARY:
    policy = os.path.join(run_folder, "policy")
    has_run = evaluated and os.path.isdir(policy) and bool(os.listdir(policy))
    return has_run, not (cell.is_baseline or has_run)
  ckpts = os.path.join(run_folder, "checkpoints")
  has_run = os.path.isdir(ckpts) and bool(os.listdir(ckpts))
  return has_run, not (cell.is_baseline or has_run and (evaluated or _trained_to_the_end(run_folder)))


def starts_afresh(cell: Cell, attempts: list[dict], run_folder: str) -> bool:
  """Whether a cell's next attempt starts from nothing, so that it may go into a pack of seeds: it
  has had no attempt and has no run folder, or every attempt it had was cut off by the study's own
  stop (the machine went back, the study was killed) and left nothing to resume from (no
  checkpoint came back). A cell with its own ended attempt (a failure, a pack's crash) or a
  checkpoint resumes alone."""
  if not attempts:
    return not os.path.exists(run_folder)
  cut_off = all(a.get("stopped") and not a.get("phase") for a in attempts)
  return cut_off and not next_attempt(cell, run_folder, [])[0]


def read_cells(folder: str) -> dict:
  """STUDY/state.json's cells as last saved; FileNotFoundError if the folder holds no study."""
  return json.load(open(os.path.join(folder, STATE)))["cells"]


def folder_parser(command: str, doc: str):
  """The parser of `python -m train.study COMMAND NAME [--root studies]` (a command that reads a
  study's folder, ROOT/NAME: status, report, timeline); its description: doc's first line."""
  import argparse  # noqa: PLC0415
  p = argparse.ArgumentParser(prog=f"python -m train.study {command}", description=doc.splitlines()[0])
  p.add_argument("name", help="the study's name (its folder under --root)")
  p.add_argument("--root", default="studies")
  return p


def no_study(folder: str, name: str, missing: str | None) -> int:
  """Says in one line that ROOT/NAME holds no study (the file missing from it); exit code 2."""
  print(f"error: no study in {folder} ({os.path.basename(missing or STATE)} is missing); start it with "
        f"python -m train.study {name}", file=sys.stderr)
  return 2


def status_counts(cells: dict) -> dict[str, int]:
  """Cells per status: done, running, queued, failed."""
  out = {"done": 0, "running": 0, "queued": 0, "failed": 0}
  for c in cells.values():
    out[c["status"]] += 1
  return out


def overview(cells: dict) -> str:
  """'N runs: D done, F failed, U not finished; A attempts'."""
  n = status_counts(cells)
  attempts = sum(len(c["attempts"]) for c in cells.values())
  return (f"{len(cells)} runs: {n['done']} done, {n['failed']} failed, {n['running'] + n['queued']} not finished "
          f"({n['running']} submitted: running or waiting for a slot); {attempts} attempts")


@dataclasses.dataclass
class StudyState:
  """STUDY/state.json: {cell id: {"status": queued|running|done|failed, "attempts": [...]}};
  running = submitted to the cluster (waiting for a slot or running)."""
  path: str
  cells: dict

  @staticmethod
  def load(folder: str, ids: list[str]) -> "StudyState":
    path = os.path.join(folder, STATE)
    old = read_cells(folder) if os.path.exists(path) else {}
    fresh = {i: {"status": "queued", "attempts": []} for i in ids}
    for i, c in old.items():
      if i in fresh:
        for a in c["attempts"]:
          if "ended" not in a:  # the study stopped while it ran
            a.update(ended=None, rc=None, phase=None, worker=None, stopped=True,
                     error="the study stopped during this attempt")
        fresh[i] = {**c, "status": "done" if c["status"] == "done" else "queued"}
    return StudyState(path, fresh)

  def save(self) -> None:
    atomic.write_json(self.path, {"cells": self.cells})

  def counts(self) -> dict[str, int]:
    return status_counts(self.cells)


def _progress(name: str, state: StudyState, t0: float, finished_now: int, running: int | None, stream) -> None:
  """One line: runs done / running / waiting for a slot / to retry / failed, elapsed, ETA; running
  None: not known (every submitted run counts as waiting). The ETA (runs finished so far a second x
  runs left) only while some run waits for a slot: where every run left is running, e.g. a pack's
  runs ending together, it would say nothing (the paper study on one GPU: "eta 2,026 s" 21 s before
  its end); the runs' own logs have theirs."""
  n, elapsed = state.counts(), time.time() - t0
  left = n["running"] + n["queued"]
  busy = min(running or 0, n["running"])
  not_running = left - busy  # waiting for a slot or to retry
  eta = f", eta {elapsed / finished_now * left:,.0f} s" if finished_now and not_running else ""
  print(f"[study] {name}: {n['done']} done, {busy} running, {n['running'] - busy} waiting, {n['queued']} to retry, "
        f"{n['failed']} failed | {elapsed:,.0f} s{eta}", file=stream, flush=True)


class StudyRunner:
  """Submits a study's unfinished cells to a Dask client and follows them to the end."""

  def __init__(self, spec: StudySpec, folder: str, client, commands=(TRAIN, EVALUATE), stream=None,
               backends: tuple[str, ...] = ("gpu", "cpu"), progress_every: float = 60.0,
               mirror_db: str | None = None, move_folders: bool = True):
    """backends: the worker kinds the cluster has; a cell whose backend is missing runs on the other;
    progress_every: seconds between progress lines while no run finishes; mirror_db: another
    database that gets every run's records too (the server's); move_folders: workers that share the
    study's filesystem move run folders into it (False: every folder comes back as a tar)."""
    self.progress_every, self.mirror_db = progress_every, mirror_db
    self.cancel = threading.Event()  # set from another thread: the study's tasks are cancelled, run() returns
    self.spec, self.folder, self.client, self.commands = spec, folder, client, commands
    self.stream = stream or sys.stdout  # as it is now, not at import
    self.backends = backends
    self.cells = {c.id: c for c in cells(spec)}
    self.submitted: list = []  # every attempt's future, in order
    self.owners: dict[str, list[str]] = {}  # an attempt's key -> the cells it runs (several: a pack)
    os.makedirs(os.path.join(folder, "runs"), exist_ok=True)
    # the handoff folder's token file stays open (locked) while this runner lives
    self.handoff, self._handoff_lock = Handoff.create(folder) if move_folders else (None, None)
    from train.study.results import write_spec  # noqa: PLC0415  (results imports this module)
    write_spec(folder, spec)
    self.state = StudyState.load(folder, list(self.cells))

  def _begin(self, cid: str) -> tuple[bytes | None, bool]:
    """Records a new attempt of a cell; (its run folder packed if it resumes, whether it trains)."""
    cell, record = self.cells[cid], self.state.cells[cid]
    local = cell_folder(self.folder, cell)
    ended = [a for a in record["attempts"] if a.get("phase")]  # not those the study's own stop cut off
    has_run, train = next_attempt(cell, local, ended)  # train False: evaluate only
    resume = pack(local) if has_run else None
    record["status"] = "running"
    record["attempts"].append({"started": time.time(), "resumed": resume is not None, "train": train})
    return resume, train

  def _resources(self, cell: Cell) -> dict:
    return {cell.backend if cell.backend in self.backends else self.backends[0]: 1}

  def _submit(self, cid: str):
    cell = self.cells[cid]
    resume, train = self._begin(cid)
    key = f"{cid}/attempt-{len(self.state.cells[cid]['attempts'])}"
    future = self.client.submit(run_cell, cell.train_args(), cell.eval_args(self.spec.eval_trials), resume, train,
                                self.commands, self.handoff, key=key, pure=False, resources=self._resources(cell))
    self.owners[key] = [cid]
    return future

  def _submit_pack(self, cids: list[str]):
    """Fresh cells that differ only in their seed (and task, early stop: packs_of), trained as one
    program (train.run --seeds [--tasks] [--early-stops])."""
    cells = [self.cells[cid] for cid in cids]
    for cid in cids:  # a folder here is what a cut-off attempt left (no checkpoint): the pack replaces it
      shutil.rmtree(cell_folder(self.folder, self.cells[cid]), ignore_errors=True)
      self._begin(cid)
      self.state.cells[cid]["attempts"][-1]["pack"] = cids
    key = f"{cids[0]}/attempt-{len(self.state.cells[cids[0]]['attempts'])}+{len(cids) - 1}"
    future = self.client.submit(run_pack, pack_train_args(cells), pack_folders(cells),
                                cells[0].eval_args(self.spec.eval_trials), self.commands, self.handoff,
                                key=key, pure=False, resources=self._resources(cells[0]))
    self.owners[key] = cids
    return future

  def _submit_all(self, cids: list[str]) -> list:
    """Submits the cells: cells starting afresh of a group that packs seeds go as one pack per set of
    seeds (again after a study's stop cut their pack off)."""
    fresh = [self.cells[cid] for cid in cids
             if starts_afresh(self.cells[cid], self.state.cells[cid]["attempts"], cell_folder(self.folder, self.cells[cid]))]
    packs = [[c.id for c in p] for p in packs_of(fresh)]
    packed = {cid for p in packs for cid in p}
    return [self._submit_pack(p) for p in packs] + [self._submit(cid) for cid in cids if cid not in packed]

  def _results(self, future) -> dict[str, dict]:
    """Each cell's result of an attempt (a pack's, one per cell); a task that raised, or whose worker
    died (distributed.KilledWorker), gives every cell of it that error."""
    cids = self.owners[future.key]
    try:
      res = future.result()
    except Exception as e:
      failed = {"rc": None, "phase": "train", "tar": None, "log_tail": "", "worker": None, "error": repr(e)}
      return {cid: failed for cid in cids}
    if "cells" not in res:
      return {cids[0]: res}
    members = pack_folders([self.cells[cid] for cid in cids])  # each cell's folder in the pack's output
    return {cid: res["cells"][m] for cid, m in zip(cids, members)}

  def _settle(self, cid: str, res: dict, stopped: bool = False) -> bool:
    """Records an attempt's outcome (res: _results'; stopped: by the study's own stop, not counted
    as a failure); True if the cell should be tried again."""
    record = self.state.cells[cid]
    attempt = record["attempts"][-1]
    db, local = ExperimentDB(os.path.join(self.folder, STUDY_DB)), cell_folder(self.folder, self.cells[cid])
    returned = receive(res, local)
    if res.get("moved") and not returned:  # moved in, then gone before the study took it
      res = {**res, "rc": res["rc"] or 1, "error": f"its run folder, moved to {res['moved']}, is gone"}
    if returned:
      attempt["returned"] = returned  # how the run folder came back: moved (a shared filesystem) or tar
      if os.path.exists(os.path.join(local, RUN_DB)):
        db.import_runs(os.path.join(local, RUN_DB), local)
        if self.mirror_db:
          ExperimentDB(self.mirror_db).import_runs(os.path.join(local, RUN_DB), local)
    attempt.update(ended=time.time(), rc=res["rc"], phase=res["phase"], worker=res["worker"],
                   error=res.get("error") or ("" if res["rc"] == 0 else res["log_tail"][-500:]))
    if stopped and res["rc"] != 0:
      attempt.update(stopped=True, error=attempt["error"] or "the study was stopped")
    if attempt.get("pack") and res["rc"] != 0:
      attempt["error"] = f"in a pack of {len(attempt['pack'])} runs (one program): {attempt['error']}"
    db.log_attempt(self.spec.name, cid, len(record["attempts"]), attempt, run_id_in(local))
    # a pack's failure uses up no run's retries: any of its runs may have failed it, and each is
    # retried alone (never packed again)
    failures = sum(1 for a in record["attempts"] if a["rc"] != 0 and not a.get("stopped") and not a.get("pack"))
    retry = res["rc"] != 0 and failures <= self.spec.retries
    record["status"] = "done" if res["rc"] == 0 else "queued" if retry else "failed"
    return retry

  def _running(self) -> int | None:
    """How many cells are running now, as the workers' heartbeats report their executing tasks (a
    pack's cells all; a task handed to a worker but waiting there for a slot is not running); None
    if the scheduler cannot say."""
    try:  # a lambda travels by value: a remote scheduler needs no import of this project
      keys = self.client.run_on_scheduler(
          lambda dask_scheduler: [ts.key for ws in dask_scheduler.workers.values() for ts in ws.executing])
    except Exception:  # noqa: BLE001  (a scheduler going away must not stop the study)
      return None
    return sum(len(self.owners.get(key, ())) for key in keys)  # this study's tasks only

  def _report(self, t0: float, finished: int) -> None:
    _progress(self.spec.name, self.state, t0, finished, self._running(), self.stream)

  def run(self) -> dict[str, int]:
    """Runs every unfinished cell; returns the final counts of done and failed cells."""
    from distributed import as_completed  # noqa: PLC0415
    t0, finished = time.time(), 0
    todo = [cid for cid, c in self.state.cells.items() if c["status"] != "done"]
    pending, submitted = as_completed(), self.submitted
    for future in self._submit_all(todo):
      submitted.append(future)
      pending.add(future)
    self.state.save()
    self._report(t0, finished)
    last = time.time()
    while not pending.is_empty():
      if self.cancel.is_set():
        self.client.cancel([f for f in submitted if not f.done()])
        break
      batch = pending.next_batch(block=False)
      if not batch:
        if time.time() - last >= self.progress_every:
          self._report(t0, finished)
          last = time.time()
        time.sleep(0.2)
        continue
      for future in batch:
        for cid, res in self._results(future).items():
          if self._settle(cid, res):  # a pack's cells are tried again one by one, from their folders
            submitted.append(self._submit(cid))
            pending.add(submitted[-1])
          else:
            finished += 1
        self.state.save()
      self._report(t0, finished)
      last = time.time()
    return self.state.counts()

  def drain(self, timeout_s: float = STOP_WAIT_S) -> int:
    """After a stop request: SIGTERM to the runs of this study on this machine (each saves a
    checkpoint and exits), then every attempt that comes back within timeout_s is recorded as
    stopped, its run folder kept for the next start; returns how many came back."""
    import psutil  # noqa: PLC0415  (a dependency of distributed)
    procs = run_processes(self.commands)
    for proc in procs:
      try:
        proc.send_signal(signal.SIGTERM)
      except psutil.Error:
        pass
    psutil.wait_procs(procs, timeout=timeout_s)
    back, t_end = 0, time.time() + 30  # the workers pack each run folder and return it
    latest = {cid: f for f in self.submitted for cid in self.owners[f.key]}  # each cell's last attempt
    for future in dict.fromkeys(latest.values()):
      cids = [cid for cid, f in latest.items() if f is future and self.state.cells[cid]["status"] == "running"]
      if not cids:
        continue  # settled already
      try:
        future.result(timeout=max(t_end - time.time(), 0.1))
      except Exception:  # noqa: BLE001  (not back in time, or lost: the next start records it as stopped)
        pass
      if future.done():
        results = self._results(future)
        for cid in cids:
          self._settle(cid, results[cid], stopped=True)
          back += 1
    self.client.cancel([f for f in self.submitted if not f.done()])
    self.state.save()
    return back


def run_processes(commands) -> list:
  """This process's descendants that run one of the commands (train.run, train.evaluate)."""
  import psutil  # noqa: PLC0415
  found = []
  for proc in psutil.Process().children(recursive=True):
    try:
      argv = proc.cmdline()
    except psutil.Error:
      continue
    if any(argv[1:1 + len(c)] == list(c) for c in commands):
      found.append(proc)
  return found


def run_until_done_or_stopped(runner: StudyRunner, stream=None) -> int:
  """Runs the study to its end (exit 0, or 1 if a run failed); on Ctrl-C or SIGTERM (which a
  scheduler sends to this process alone) its runs on this machine are stopped with a checkpoint and
  recorded (StudyRunner.drain), exit 130 / 143. The client, and a cluster it started, close either way."""
  stream = stream or sys.stderr  # as it is now, not at import
  signals: list[int] = []

  def on_sigterm(signum, _):
    signals.append(signum)
    raise KeyboardInterrupt

  main = threading.current_thread() is threading.main_thread()
  old = signal.signal(signal.SIGTERM, on_sigterm) if main else None
  try:
    counts = runner.run()
  except KeyboardInterrupt:
    print("\nstopping: the running runs save a checkpoint and come back ...", file=stream, flush=True)
    back = runner.drain()
    n = runner.state.counts()
    print(f"interrupted: {n['done']} of {sum(n.values())} runs done, {back} stopped with their checkpoints; the "
          "same command continues the study", file=stream, flush=True)
    return 143 if signals else 130
  finally:
    if main:
      signal.signal(signal.SIGTERM, old)
    cluster = getattr(runner.client, "cluster", None)
    runner.client.close()
    if cluster is not None:
      cluster.close()
  print(f"study {runner.spec.name}: {counts['done']} runs done, {counts['failed']} failed -> {runner.folder} "
        "(state.json)", flush=True)
  return 0 if counts["failed"] == 0 else 1

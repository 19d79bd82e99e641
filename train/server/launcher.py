"""The server's launches, run on a Dask cluster by the study executor's worker function
(`train.study.worker.run_in_place`), never in the server's process: queued launches are submitted,
finished ones recorded in the database's `launches` table. A launch that cannot start is recorded
as failed, and the queue goes on. Launches found running when the server starts (it stopped while
they ran) are reconciled with what is left of them (Launcher.start)."""

from __future__ import annotations

import os
import signal
import socket
import sys
import threading
import time
import traceback

from train.db import FINISHED, ExperimentDB, utc_now
from train.evaluation import EVAL_TRIALS
from train.study.spec import Cell, cells, study_from_dict
from train.study.worker import EVALUATE, TRAIN, read_pid_file, run_in_place

STOPPED = 143  # train.run's exit code after SIGTERM (checkpoint written, policy exported)


def study_of(spec: dict):
  """The study a study launch holds ({"yaml": text, "overrides": [KEY=VALUE]}), validated like
  `python -m train.study`; ConfigError names the faulty key."""
  from mjx_tracks.envs.config import apply_override, load_yaml  # noqa: PLC0415
  raw = load_yaml(spec.get("yaml") or "", "the study YAML", "yaml") or {}
  for item in spec.get("overrides", []):
    raw = apply_override(raw, item)
  return study_from_dict(raw)


def cell_of(spec: dict) -> Cell:
  """The run a launch spec describes ({task, algo, preset, library, steps, seed, overrides, hp, early_stop}),
  checked like a study's; ConfigError names the faulty key."""
  group = {"name": "launch", "algo": spec.get("algo", "ppo"), "preset": spec.get("preset", "cpu"),
           "steps": [spec.get("steps", 2048)], "early_stop": spec.get("early_stop", ""),
           "set": list(spec.get("overrides", [])), "backend": spec.get("backend", "cpu"),
           **{k: spec[k] for k in ("hp", "library") if k in spec}}  # else the study's defaults
  study = study_from_dict({"name": "launch", "tasks": [spec.get("task")], "seeds": [spec.get("seed", 0)],
                           "groups": [group], "eval_trials": max(spec.get("eval_trials", EVAL_TRIALS), 1),
                           "baselines": []})
  (cell,) = cells(study)  # the study's one run, as a study would run it
  return cell


class Launcher:
  """Submits the database's queued launches to a Dask client and records how they end."""

  def __init__(self, db_path: str, runs_root: str, client, backends: tuple[str, ...] = ("cpu",),
               commands=(TRAIN, EVALUATE), poll_s: float = 1.0):
    self.db, self.runs_root, self.client = ExperimentDB(db_path), os.path.abspath(runs_root), client
    self.backends, self.commands, self.poll_s = backends, commands, poll_s
    self.futures: dict[int, object] = {}  # launch id -> a Dask future, or a thread running a study
    self.lock, self.done = threading.Lock(), threading.Event()
    self.thread = threading.Thread(target=self._loop, name="launcher", daemon=True)

  def start(self) -> "Launcher":
    """Reconciles each launch that was running when the server stopped (_reconcile), stops the
    process still working on a cancelled launch's run (cancelled as the server stopped, before it
    could stop the run), then follows the queue in a thread."""
    for launch in self.db.launches("running"):
      self._reconcile(launch)
    for launch in self.db.launches("cancelled"):
      stop_named_process(launch["out_dir"])
    self.thread.start()
    return self

  def _reconcile(self, launch: dict) -> None:
    """A launch left running: followed again if its task is still on the cluster (one that outlived
    the server) or its process still runs on this host; done (or queued for its evaluation) if its
    run finished meanwhile; else queued again, to resume where a checkpoint exists."""
    lid, out = launch["id"], launch["out_dir"] or ""
    process = named_process(out)
    if self._cluster_knows(f"launch-{lid}"):
      from distributed import Future  # noqa: PLC0415
      self.futures[lid] = Future(f"launch-{lid}", self.client)
      return
    if process:
      self.futures[lid] = ProcessWatch(process["pid"], process["phase"], out, self.db)
      return
    run = run_in(self.db, out)
    if launch["kind"] in ("run", "resume") and run and run["status"] in FINISHED:
      self._finished_meanwhile(launch, run)
      return
    resumable = launch["kind"] in ("run", "resume") and os.path.isdir(os.path.join(out, "checkpoints"))
    kind = "resume" if resumable else launch["kind"]
    self.db.set_launch(lid, status="queued", kind=kind,
                       out_dir=out if resumable or kind in ("evaluate", "study") else None,
                       error=f"queued again ({kind}) after a server restart")

  def _finished_meanwhile(self, launch: dict, run: dict) -> None:
    """Its training ended while no server watched: done, or queued to evaluate if it asked for an
    evaluation that has no trials yet."""
    wants = launch["spec"].get("eval_trials", EVAL_TRIALS) > 0 and not self.db.eval_groups(run["run_id"])
    if wants:
      self.db.set_launch(launch["id"], status="queued", kind="evaluate",
                         error="its training finished while the server was down; queued to evaluate")
    else:
      self.db.set_launch(launch["id"], status="done", ended=utc_now(), rc=0,
                         error="finished while the server was down")

  def _cluster_knows(self, key: str) -> bool:
    try:
      return bool(self.client.run_on_scheduler(lambda dask_scheduler: key in dask_scheduler.tasks))
    except Exception:  # noqa: BLE001  (a cluster that cannot say knows nothing we can follow)
      return False

  def stop(self) -> None:
    self.done.set()
    self.thread.join(timeout=10)

  def _loop(self) -> None:
    while not self.done.wait(self.poll_s):
      try:
        with self.lock:
          self._tick()
      except Exception:  # noqa: BLE001  (the queue must outlive any one failure: say it and go on)
        print(f"launcher: {traceback.format_exc(limit=3)}", file=sys.stderr, flush=True)

  def _tick(self) -> None:
    for launch in self.db.launches("queued"):
      try:
        self._submit(launch)
      except Exception as e:  # noqa: BLE001  (recorded as the launch's error; the next one starts)
        self.futures.pop(launch["id"], None)
        self.db.set_launch(launch["id"], status="failed", ended=utc_now(),
                           error=f"could not start: {type(e).__name__}: {str(e)[:300]}")
    for lid, future in list(self.futures.items()):  # a cancelled run that had no process yet: CancelWatch
      if (not future.is_alive()) if isinstance(future, threading.Thread) else future.done():
        self._settle(lid, future)

  def _submit(self, launch: dict) -> None:
    spec, kind = launch["spec"], launch["kind"]
    if kind == "study":
      self._start_study(launch)
      return
    cell = cell_of(spec)
    out = launch["out_dir"] or self._new_folder(cell, launch["id"])
    # 0 trials: no evaluation suite after training; an evaluate launch always evaluates
    trials = spec.get("eval_trials", EVAL_TRIALS) or (EVAL_TRIALS if kind == "evaluate" else 0)
    eval_args = ["--suite", "--trials", str(trials)] if trials else []
    backend = cell.backend if cell.backend in self.backends else self.backends[0]
    self.futures[launch["id"]] = self.client.submit(
        run_in_place, cell.train_args(), eval_args, out, self.db.path, kind == "resume", kind != "evaluate",
        self.commands, key=f"launch-{launch['id']}", pure=False, resources={backend: 1})
    self.db.set_launch(launch["id"], status="running", started=utc_now(), out_dir=out)

  def _start_study(self, launch: dict) -> None:
    """A study launch: the study executor (train.study) on this launcher's cluster, in a thread;
    its runs' records are mirrored into the server's database. A study started again skips its
    finished runs."""
    spec = study_of(launch["spec"])
    folder = launch["out_dir"] or os.path.join(self.runs_root, "studies", spec.name)
    os.makedirs(folder, exist_ok=True)
    outcome: dict = {}

    from train.study.executor import StudyRunner  # noqa: PLC0415
    log = open(os.path.join(folder, "study.log"), "a")
    runner = StudyRunner(spec, folder, self.client, self.commands, log, self.backends, mirror_db=self.db.path)

    def run() -> None:
      try:
        outcome["counts"] = runner.run()
      except Exception as e:  # noqa: BLE001  (recorded as the launch's error)
        outcome["error"] = repr(e)
      finally:
        log.close()

    thread = threading.Thread(target=run, name=f"study-{launch['id']}", daemon=True)
    thread.outcome, thread.runner = outcome, runner
    self.futures[launch["id"]] = thread
    self.db.set_launch(launch["id"], status="running", started=utc_now(), out_dir=folder)
    thread.start()

  def _new_folder(self, cell: Cell, launch_id: int) -> str:
    """RUNS/<task>-<algo>-s<seed>-L<launch>[-N]: a folder no run has used."""
    base = os.path.join(self.runs_root, f"{cell.task}-{cell.algo}-s{cell.seed}-L{launch_id}")
    path, n = base, 1
    while os.path.exists(path):
      n += 1
      path = f"{base}-{n}"
    return path

  def _settle(self, launch_id: int, future) -> None:
    del self.futures[launch_id]
    if isinstance(future, threading.Thread):  # a study
      counts, error = future.outcome.get("counts") or {}, future.outcome.get("error", "")
      ok = not error and counts.get("failed", 1) == 0
      res = {"rc": 0 if ok else 1, "log_tail": error or f"{counts.get('failed')} runs failed"}
    else:
      try:
        res = future.result()
      except Exception as e:  # noqa: BLE001  (cancelled, or its worker died)
        res = {"rc": None, "log_tail": repr(e)}
    if isinstance(future, ProcessWatch) and future.phase == "train" and res["rc"] == 0:
      launch = self.db.launch(launch_id)  # its evaluation never started: the worker died with the server
      run = run_in(self.db, launch["out_dir"])
      if run is not None and launch["status"] != "cancelled":
        return self._finished_meanwhile(launch, run)
    cancelled = self.db.launch(launch_id)["status"] == "cancelled"
    stopped = res["rc"] in (STOPPED, -signal.SIGTERM)  # saved and stopped, or stopped before it had set up
    status = "cancelled" if cancelled else "done" if res["rc"] == 0 else "stopped" if stopped else "failed"
    self.db.set_launch(launch_id, status=status, ended=utc_now(), rc=res["rc"],
                       error="" if res["rc"] == 0 else res["log_tail"][-500:])

  def cancel(self, launch_id: int) -> str:
    """Cancels a queued launch, or stops a running one (SIGTERM to its run); returns what it did."""
    with self.lock:
      launch = self.db.launch(launch_id)  # KeyError if unknown
      if launch["status"] not in ("queued", "running"):
        return f"launch {launch_id} is {launch['status']}; nothing to cancel"
      self.db.set_launch(launch_id, status="cancelled", ended=utc_now())
      task = self.futures.get(launch_id)
      if isinstance(task, threading.Thread):
        task.runner.cancel.set()  # a study: its queued runs are cancelled
      elif isinstance(task, ProcessWatch):
        task.cancel()  # SIGTERM to its process
      elif task is not None:
        task.cancel()  # still waiting for a slot; or running: Dask forgets it, its thread goes on
        if not stop_run_in(self.db, launch["out_dir"]):
          self.futures[launch_id] = CancelWatch(self.db, launch["out_dir"])  # its run may be starting
      return f"launch {launch_id} cancelled"


def run_in(db: ExperimentDB, out_dir: str | None) -> dict | None:
  """The database's record of the run in out_dir (the newest, if several), or None."""
  found = [r for r in db.runs() if out_dir and os.path.abspath(r["out_dir"]) == os.path.abspath(out_dir)]
  return found[-1] if found else None


def _alive(pid: int) -> bool:
  import psutil  # noqa: PLC0415  (a dependency of distributed)
  try:
    return psutil.Process(pid).status() != psutil.STATUS_ZOMBIE
  except psutil.Error:
    return False


class ProcessWatch:
  """A launch's process found running after a server restart, which no Dask future knows: done
  when the process is gone, its outcome read from the run's record."""

  def __init__(self, pid: int, phase: str, out: str, db: ExperimentDB):
    self.pid, self.phase, self.out, self.db = pid, phase, out, db

  def done(self) -> bool:
    return not _alive(self.pid)

  def cancel(self) -> None:
    stop_run_in(self.db, self.out)

  def result(self) -> dict:
    run = run_in(self.db, self.out)
    status = run["status"] if run else None
    rc = 0 if status in FINISHED else STOPPED if status == "interrupted" else 1
    log = self.out + ".log"
    tail = open(log).read()[-2000:] if os.path.exists(log) else ""
    return {"rc": rc, "log_tail": tail or f"its run ended {status}"}


class CancelWatch:
  """A cancelled launch whose run no process was found for yet: its task may be starting it (or
  between its training and its evaluation). Each tick (done()) looks again and stops the process it
  finds; done once it has, or after patience_s."""

  def __init__(self, db: ExperimentDB, out: str | None, patience_s: float = 120.0):
    self.db, self.out, self.until = db, out, time.monotonic() + patience_s

  def done(self) -> bool:
    return stop_run_in(self.db, self.out) or time.monotonic() > self.until

  def cancel(self) -> None:
    pass  # cancelled already: done() stops its run

  def result(self) -> dict:
    return {"rc": None, "log_tail": "cancelled"}


def named_process(out_dir: str | None) -> dict | None:
  """The run's pid file ({"pid", "host", "phase"}: the phase the launch's worker runs, training or
  evaluation) where it names a live process of this host that works on out_dir (the folder is in its
  command line: a pid file left by a worker that died may name a pid the system has given another
  process since); else None."""
  import psutil  # noqa: PLC0415  (a dependency of distributed)
  process = read_pid_file(out_dir) if out_dir else None
  if not process or process["host"] != socket.gethostname() or not _alive(process["pid"]):
    return None
  try:
    argv = psutil.Process(process["pid"]).cmdline()
  except psutil.Error:
    return None
  return process if any(a == out_dir or os.path.abspath(a) == os.path.abspath(out_dir) for a in argv) else None


def stop_named_process(out_dir: str | None) -> bool:
  """SIGTERM to the process named_process(out_dir) finds; True if sent."""
  process = named_process(out_dir)
  if process:
    os.kill(process["pid"], signal.SIGTERM)
  return process is not None


def stop_run_in(db: ExperimentDB, out_dir: str | None) -> bool:
  """SIGTERM to the process working on the run in `out_dir` (this host only): the one its pid file
  names, else the running training the database knows; True if sent."""
  if stop_named_process(out_dir):
    return True
  run = run_in(db, out_dir)
  if run and run["status"] == "running" and run["host"] == socket.gethostname() and run["pid"]:
    os.kill(run["pid"], signal.SIGTERM)
    return True
  return False

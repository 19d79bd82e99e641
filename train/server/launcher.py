"""The server's launches, run on a Dask cluster by the study executor's worker function
(`train.study.worker.run_in_place`), never in the server's process: queued launches are submitted,
finished ones recorded in the database's `launches` table. Launches found running when the server
starts (it stopped while they ran) are followed again if their run still runs, else queued again
to resume from their checkpoints."""

from __future__ import annotations

import os
import signal
import socket
import threading

from train.db import ExperimentDB, utc_now
from train.evaluate import EVAL_TRIALS
from train.study.spec import Cell, study_from_dict
from train.study.worker import EVALUATE, TRAIN, run_in_place

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
  """The run a launch spec describes ({task, algo, preset, steps, seed, overrides, early_stop}),
  checked like a study's; ConfigError names the faulty key."""
  group = {"name": "launch", "algo": spec.get("algo", "ppo"), "preset": spec.get("preset", "cpu"),
           "steps": [spec.get("steps", 2048)], "early_stop": spec.get("early_stop", ""),
           "set": list(spec.get("overrides", [])), "backend": spec.get("backend", "cpu")}
  study = study_from_dict({"name": "launch", "tasks": [spec.get("task")], "seeds": [spec.get("seed", 0)],
                           "groups": [group], "eval_trials": max(spec.get("eval_trials", EVAL_TRIALS), 1)})
  g = study.groups[0]
  return Cell(g.name, study.tasks[0], g.steps[0], study.seeds[0], g.algo, g.preset, g.early_stop, g.set, g.backend)


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
    """Takes up what was running when the server stopped: a run whose process still runs (on a
    cluster that outlived the server) is followed again; any other is queued again, to resume
    where a checkpoint exists. Then follows the queue in a thread."""
    from distributed import Future  # noqa: PLC0415
    alive = {os.path.abspath(r["out_dir"]) for r in self.db.runs() if r["status"] == "running"}
    for launch in self.db.launches("running"):
      out = launch["out_dir"] or ""
      if os.path.abspath(out) in alive:
        self.futures[launch["id"]] = Future(f"launch-{launch['id']}", self.client)
        continue
      resumable = launch["kind"] in ("run", "resume") and os.path.isdir(os.path.join(out, "checkpoints"))
      kind = "resume" if resumable else launch["kind"]
      self.db.set_launch(launch["id"], status="queued", kind=kind,
                         out_dir=out if resumable or kind in ("evaluate", "study") else None,
                         error=f"queued again ({kind}) after a server restart")
    self.thread.start()
    return self

  def stop(self) -> None:
    self.done.set()
    self.thread.join(timeout=10)

  def _loop(self) -> None:
    while not self.done.wait(self.poll_s):
      with self.lock:
        for launch in self.db.launches("queued"):
          self._submit(launch)
        for lid, future in list(self.futures.items()):
          if (not future.is_alive()) if isinstance(future, threading.Thread) else future.done():
            self._settle(lid, future)
          else:
            launch = self.db.launch(lid)
            if launch["status"] == "cancelled":  # its run may have started since the cancel
              stop_run_in(self.db, launch["out_dir"])

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
    cancelled = self.db.launch(launch_id)["status"] == "cancelled"
    status = "cancelled" if cancelled else "done" if res["rc"] == 0 else "stopped" if res["rc"] == STOPPED else "failed"
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
      elif task is not None:
        task.cancel()  # still waiting for a slot
        stop_run_in(self.db, launch["out_dir"])
      return f"launch {launch_id} cancelled"


def stop_run_in(db: ExperimentDB, out_dir: str | None) -> bool:
  """SIGTERM to the training process of the run in `out_dir` (this host only); True if sent."""
  for run in db.runs():
    if out_dir and os.path.abspath(run["out_dir"]) == os.path.abspath(out_dir) and run["status"] == "running":
      if run["host"] == socket.gethostname() and run["pid"]:
        os.kill(run["pid"], signal.SIGTERM)
        return True
  return False

"""A pack's evaluations (train.study.worker): every run that ended in one process, its trials in
the pack's database; each run gets the process's exit code and output. A run folder comes back
moved where the worker shares the study's filesystem, else as a tar."""

import dataclasses
import os
import time

from train.study import worker

STAND_IN = """import sys
runs = sys.argv[1:sys.argv.index("--suite")]
db = sys.argv[sys.argv.index("--db") + 1]
for run in runs:
  open(run + "/evaluated", "w").write(db)
  print("evaluated", run)
sys.exit(3 if any(run.endswith("bad") for run in runs) else 0)
"""


def test_a_packs_runs_are_evaluated_in_one_process_and_each_keeps_its_exit_code_and_output(tmp_path):
  script = tmp_path / "evaluate_stand_in.py"
  script.write_text(STAND_IN)
  folders = {m: str(tmp_path / m) for m in ("a", "b", "c")}
  for folder in folders.values():
    os.makedirs(folder)
  done = worker._evaluate_together(folders, ["--suite"], (str(script),), "pack.sqlite", str(tmp_path))
  assert {m: code for m, (_, code, _) in done.items()} == {"a": 0, "b": 0, "c": 0}
  assert all(f"evaluated {f}" in done[m][2] for m in folders for f in folders.values())  # one process's output
  assert all(open(os.path.join(f, "evaluated")).read() == "pack.sqlite" for f in folders.values())
  folders["bad"] = str(tmp_path / "bad")
  os.makedirs(folders["bad"])
  assert {code for _, code, _ in worker._evaluate_together(folders, ["--suite"], (str(script),), "x", str(tmp_path)).values()} == {3}


AWAITING = """import sys, time
runs = sys.argv[1:sys.argv.index("--suite")]
assert sys.argv[-1] == "--await-runs"
if runs[0].endswith("dies"):
  sys.exit(7)  # as one that fails while it compiles, before it is told the runs
print("compiled", flush=True)
named = [line.strip() for line in sys.stdin if line.strip()]
for run in named:
  open(run + "/evaluated", "w").write("beside")
print("evaluated", *named)
"""


def test_a_packs_evaluation_beside_its_training_evaluates_the_runs_it_is_told_once_the_training_ended(tmp_path):
  """EarlyEvaluation (worker.run_pack on a GPU worker): the process starts with every run of the pack
  and waits (while the training runs); `finish` names the runs that ended and returns the process's
  exit code and output for each. None ended: it is stopped, nothing evaluated. A process that ended
  before it was told: None (run_pack then evaluates in a new process)."""
  script = tmp_path / "awaiting.py"
  script.write_text(AWAITING)
  folders = {m: str(tmp_path / m) for m in ("a", "b", "c")}
  for folder in folders.values():
    os.makedirs(folder)
  beside = worker.EarlyEvaluation(list(folders.values()), ["--suite"], (str(script),), "pack.sqlite", str(tmp_path))
  time.sleep(0.5)
  assert beside.proc.poll() is None  # waiting to be told
  done = beside.finish({m: folders[m] for m in ("a", "c")})
  assert {m: code for m, (_, code, _) in done.items()} == {"a": 0, "c": 0}
  assert f"evaluated {folders['a']} {folders['c']}" in done["a"][2] and "compiled" in done["c"][2]
  assert sorted(os.listdir(tmp_path / "a")) == ["evaluated"] and not os.listdir(tmp_path / "b")
  os.makedirs(tmp_path / "idle")
  idle = worker.EarlyEvaluation(list(folders.values()), ["--suite"], (str(script),), "x", str(tmp_path / "idle"))
  assert idle.finish({}) == {} and idle.proc.returncode is not None  # stopped: its training ended no run
  assert not os.path.exists(tmp_path / "b" / "evaluated")
  dead = worker.EarlyEvaluation([str(tmp_path / "dies")], ["--suite"], (str(script),), "x", str(tmp_path / "idle"))
  dead.proc.wait()
  assert dead.finish({"dies": str(tmp_path / "dies")}) is None


def _files(folder) -> list[str]:
  return sorted(os.path.relpath(os.path.join(d, f), folder) for d, _, fs in os.walk(folder) for f in fs)


def test_a_worker_sharing_the_studys_filesystem_moves_the_run_folder_and_one_elsewhere_sends_a_tar(tmp_path):
  handoff, lock = worker.Handoff.create(str(tmp_path / "study"))

  def run_folder(name: str) -> str:
    folder = tmp_path / name
    (folder / "checkpoints" / "8").mkdir(parents=True)
    (folder / "checkpoints" / "8" / "state.bin").write_bytes(os.urandom(4096))
    (folder / "run.json").write_text("{}")
    return str(folder)

  moved = worker._outcome(run_folder("a"), 0, "evaluate", "its output", handoff)
  assert moved["tar"] is None and os.path.dirname(moved["moved"]) == handoff.folder
  assert not os.path.exists(tmp_path / "a")
  elsewhere = dataclasses.replace(handoff, folder=str(tmp_path / "not-here"))  # another machine: no such folder
  sent = worker._outcome(run_folder("b"), 0, "evaluate", "its output", elsewhere)
  assert "moved" not in sent and sent["tar"] and os.path.isdir(tmp_path / "b")
  for res, name, how in ((moved, "got-a", "moved"), (sent, "got-b", "tar")):
    got = tmp_path / name
    got.mkdir()
    (got / "stale").write_text("an earlier attempt's")  # replaced by what came back
    assert worker.receive(res, str(got)) == how
    assert _files(got) == ["checkpoints/8/state.bin", "run.json", "study-attempts.log"]
    assert (got / "study-attempts.log").read_text() == "its output"
  assert os.listdir(handoff.folder) == [worker.Handoff.TOKEN]  # taken: nothing left behind
  assert worker.receive({**sent, "tar": None}, str(tmp_path / "nothing")) is None
  kept = tmp_path / "got-a"
  assert worker.receive(moved, str(kept)) is None and _files(kept)  # gone since: the folder there is kept
  # another study process on the folder while this one runs: neither removes the other's
  other, other_lock = worker.Handoff.create(str(tmp_path / "study"))
  assert other.shared() and handoff.shared() and other.folder != handoff.folder
  worker._outcome(run_folder("c"), 0, "evaluate", "", handoff)  # moved in after its process ended ...
  lock.close()
  other_lock.close()
  again, again_lock = worker.Handoff.create(str(tmp_path / "study"))  # ... removed by the next start
  assert again.shared() and not handoff.shared() and not other.shared()
  assert os.listdir(os.path.dirname(again.folder)) == [os.path.basename(again.folder)]
  again_lock.close()

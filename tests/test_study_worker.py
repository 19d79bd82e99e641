"""A pack's evaluations (train.study.worker): every run that ended in one process, its trials in
the pack's database; each run gets the process's exit code and output."""

import os

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

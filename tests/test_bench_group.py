"""`python -m train.bench group`: N runs as one program against single runs, each process timed;
every run of both kinds trains its whole budget, and the figures follow from the rows."""

import json

from helpers import TRAIN_TINY

from train import db as dbmod
from train.bench.__main__ import main


def test_the_group_bench_times_single_runs_and_one_program_of_all(tmp_path, capsys):
  out, work = str(tmp_path / "group.json"), tmp_path / "work"
  work.mkdir()
  assert main(["group", "--runs", "2", "--singles", "1", "--steps", "1024", "--warm", "--work", str(work),
               "--out", out, "--", *TRAIN_TINY, "--probe-every", "512", "--checkpoint-every", "0"]) == 0
  result = json.load(open(out))
  single, group = result["rows"]
  assert single["mode"] == "single" and group == {"mode": "group", "runs": 2, "process_wall_s": group["process_wall_s"]}
  assert result["group_in_singles"] == round(group["process_wall_s"] / single["process_wall_s"], 2)
  assert result["group_speedup"] == round(2 * single["process_wall_s"] / group["process_wall_s"], 2)
  for name, seeds in (("single-s0", {0}), ("group", {0, 1})):  # every run trained its whole budget
    runs = dbmod.ExperimentDB(str(work / f"{name}.sqlite")).runs()
    assert {r["seed"] for r in runs} == seeds and all(r["status"] == "done" for r in runs)
    assert all(json.loads(r["final_json"])["step"] == 1024 for r in runs)
  assert "--early-stop none" in " ".join(result["train_args"])


def test_the_group_bench_refuses_a_group_of_one_in_one_line(capsys):
  assert main(["group", "--runs", "1"]) == 2
  assert capsys.readouterr().err.startswith("error: --runs >= 2")

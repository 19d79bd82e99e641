"""`python -m train.study timeline`, read from a committed study (results/studies/paper-packed: the
paper study on one H200 on 2026-11-28, two programs side by side). The figures it must give are
those read from that study's database by hand on the day (docs/benchmarks.md): the PPO program ended
at 712 s, the SAC program's runs ended their training at 975-982 s and its evaluations at 1,033 s."""

import os

from train.study import timeline
from train.study.__main__ import main as study_main

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
STUDIES = os.path.join(ROOT, "results", "studies")


def test_the_paper_study_on_one_gpu_reads_as_two_programs_with_the_figures_found_by_hand():
  progs = timeline.programs(os.path.join(STUDIES, "paper-packed"))
  assert [len(p.cells) for p in progs] == [40, 20] and all(p.worker == "gpu0" for p in progs)
  sac, ppo = progs
  t0 = min(p.started for p in progs)
  assert round(sac.ended - t0) == 1_033 and round(ppo.ended - t0) == 712
  assert 975 <= sac.trained - t0 <= 983 and ppo.trained < ppo.ended
  assert sac.compiled is None and ppo.compiled is None  # run before train.run recorded its compilation
  assert all(c.startswith("paper-sac") for c in sac.cells) and all(c.startswith("ppo/") for c in ppo.cells)


def test_the_command_prints_one_line_per_program_and_refuses_a_missing_study(capsys):
  assert study_main(["timeline", "paper-packed", "--root", STUDIES]) == 0
  said = capsys.readouterr().out.splitlines()
  assert said[0] == ("study paper-packed: 1,033 s from its first start to its last end; 2 programs of 60 runs "
                     "(s from the first start; -: not recorded)")
  # ... then its longest run's clock at its last report: 728 s of training, 127 s besides (855 s)
  assert said[2].split() == ["paper-sac/asc-inc-cog/20000/s0", "+39", "40", "gpu0", "0", "-", "982", "1,033", "728", "127"]
  assert study_main(["timeline", "nope", "--root", STUDIES]) == 2
  err = capsys.readouterr().err
  assert "no study in" in err and "state.json is missing" in err and len(err.strip().splitlines()) == 1


def test_a_runs_clock_splits_into_training_and_the_rest():
  """Reports at 1,000 steps (50 s, 40 steps/s) and 2,000 (80 s, 50 steps/s): 25 + 20 s of training,
  35 s besides; nothing where a report has no rate or there is none."""
  assert timeline.run_clock([(1000, 50.0, 40.0), (2000, 80.0, 50.0)]) == (45.0, 35.0)
  assert timeline.run_clock([]) is None and timeline.run_clock([(1000, 50.0, None)]) is None
  sac = timeline.programs(os.path.join(STUDIES, "paper-packed"))[0]
  assert abs(sum(sac.clock) - 855) < 1  # "the SAC pack's clock read 855 s at its last step" (docs/benchmarks.md)


def test_a_programs_clock_is_its_longest_runs_not_a_run_stopped_early():
  """A pack whose first run stopped at 1,000 steps (as the paper study's early-stopped SAC runs do):
  the clock shown is that of the first run that trained to the end, not the one whose last report
  was logged a little later."""
  members = [(f"c{i}", 1, {"started": 0.0, "ended": 800.0}) for i in range(3)]
  runs = {("c0", 1): "early", ("c1", 1): "whole", ("c2", 1): "also-whole"}
  reports = {"early": [(1000, 44.0, 25.0)], "whole": [(1000, 44.0, 25.0), (20000, 752.0, 40.0)],
             "also-whole": [(1000, 44.0, 25.0), (20000, 752.4, 38.0)]}
  prog = timeline._program(members, runs, {}, reports)
  assert prog.clock == timeline.run_clock(reports["whole"]) and prog.clock[0] > 500


def test_a_study_without_its_database_yet_shows_when_its_programs_started(tmp_path):
  """A study whose first attempt has not ended has state.json and no study.sqlite yet: its
  programs' starts and ends from state.json, no run events."""
  import shutil
  folder = tmp_path / "paper-packed"
  folder.mkdir()
  shutil.copy(os.path.join(STUDIES, "paper-packed", "state.json"), folder / "state.json")
  progs = timeline.programs(str(folder))
  assert [len(p.cells) for p in progs] == [40, 20]
  assert all(p.compiled is None and p.trained is None and p.ended is not None for p in progs)


def test_status_and_report_of_a_missing_study_say_so_in_one_line(capsys):
  for command in ("status", "report"):
    assert study_main([command, "nope", "--root", STUDIES]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and "nope" in err and len(err.strip().splitlines()) == 1, (command, err)

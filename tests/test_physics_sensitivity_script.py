"""scripts/analysis/physics_sensitivity.py: its settings, figures and pairing against hand-made
trials, and its refusals (the rollouts it drives are train.evaluate's, tested elsewhere)."""

import os
import sys

import pytest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "scripts", "analysis"))
from physics_sensitivity import main, outcomes, paired, variants  # noqa: E402

OUT = "<out>"  # the report path each refused command names: tmp_path / "x", written by none of them


def test_variants_take_physics_keys_only_under_new_names():
  got = variants(["a:physics.solver_iterations=4; physics.ls_iterations=6", "b:physics.timestep=0.005"])
  assert got == {"a": ["physics.solver_iterations=4", "physics.ls_iterations=6"], "b": ["physics.timestep=0.005"]}
  for bad in (["a:physics.timestep=0.005", "a:physics.timestep=0.01"],  # a repeated name
              ["configured:physics.timestep=0.005"],  # the name of the configured physics
              ["a:randomization.mass=[0.8, 0.8]"],  # not a physics key
              ["a:"], ["physics.timestep=0.005"]):  # no setting; no name
    with pytest.raises(ValueError):
      variants(bad)


def test_outcomes_and_pairing_count_each_trial():
  # 4 trials: 0 succeeds, 1 tips over, 2 collides, 3 runs out of time
  trials = {"success": [1.0, 0.0, 0.0, 0.0], "progress": [1.0, 0.2, 0.4, 0.8], "tipped_over": [0.0, 1.0, 0.0, 0.0],
            "collided": [0.0, 0.0, 1.0, 0.0], "length": [30.0, 10.0, 50.0, 50.0]}
  got = outcomes(trials)
  assert got == {"success": 0.25, "progress": 0.6, "tipped_over": 1, "collided": 1, "timed_out": 1, "length": 35.0,
                 "per_trial_success": [1, 0, 0, 0]}
  other = outcomes({**trials, "success": [0.0, 0.0, 1.0, 1.0]})
  assert paired(got, other) == {"gained": 2, "lost": 1}


@pytest.mark.parametrize("argv, words", [
    (["--scene", "hardest", "--variant", "a:physics.timestep=0.005", "--out", OUT], "give run folders"),
    (["--baseline", "zero", "--scene", "hardest", "--variant", "a:physics.timestep=0.005", "--out", OUT], "give run folders"),
    (["r", "--set", "episode.max_steps=9", "--scene", "hardest", "--variant", "a:physics.timestep=0.005", "--out", OUT],
     "--set applies to a baseline"),
    (["--baseline", "zero", "--task", "asc-inc-cog", "--scene", "hardest", "--variant", "a:control.period=0.5",
      "--out", OUT], "only physics.KEY=VALUE"),
    (["--baseline", "zero", "--task", "asc-inc-cog", "--scene", "hardest", "--variant", "a:physics.timestep=-1",
      "--out", OUT], "physics.timestep"),
    (["--baseline", "zero", "--task", "asc-inc-cog", "--scene", "hardest+no-such-case", "--variant",
      "a:physics.timestep=0.005", "--out", OUT], "unknown robustness case"),
    (["--baseline", "zero", "--task", "asc-inc-cog", "--scene", "hardest", "--variant", "a:physics.timestep=0.005",
      "--trials", "0", "--out", OUT], "--trials must be at least 1")])
def test_wrong_arguments_fail_with_one_line_naming_them(argv, words, tmp_path, capsys):
  argv = [str(tmp_path / "x") if a == OUT else a for a in argv]
  with pytest.raises(SystemExit) as e:
    main(argv)
  assert e.value.code == 2
  err = capsys.readouterr().err.strip().splitlines()[-1]
  assert words in err
  assert not os.path.exists(tmp_path / "x")

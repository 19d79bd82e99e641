"""The physics gate (`python -m train.bench gate`): its oracles pass under the default physics and
fail under settings that break the physics (one solver and one line-search iteration). Its flat-
ground oracles are tests/test_track_model.py's."""

import pytest

from train.bench import gate
from train.bench.result import BenchInputError
from train.bench.__main__ import main as bench_main


def test_the_default_physics_passes_and_one_solver_iteration_fails_against_the_c_engine():
  good = gate.c_engine_check(gate.physics_of([]))
  bad = gate.c_engine_check(gate.physics_of(["physics.solver_iterations=1", "physics.ls_iterations=1"]))
  assert all(c.ok for c in good) and good[0].value < 0.001 and good[1].value < 0.005  # MJX vs C, same options
  assert not any(c.ok for c in bad) and bad[0].value > 0.1  # m: the fall goes wrong


def test_the_gate_takes_physics_settings_only(capsys):
  assert bench_main(["gate", "--set", "reward.cog_scale=1"]) == 2
  assert "physics settings only" in capsys.readouterr().err
  with pytest.raises(BenchInputError, match="solver_iterations"):
    gate.physics_of(["physics.solver_iterations=0"])
  with pytest.raises(BenchInputError, match="must divide"):
    gate.physics_of(["physics.timestep=0.019230769230769232"])  # 0.25 s / 13: a control period, not 0.05 s

"""The physics gate (`python -m train.bench gate`): its oracles pass under the default physics and
fail under settings that break the physics (one solver and one line-search iteration)."""

import pytest

from train.bench import gate
from train.bench.__main__ import main as bench_main


def test_the_default_physics_passes_and_one_solver_iteration_fails_against_the_c_engine():
  good = gate.c_engine_check(gate.physics_of([]))
  bad = gate.c_engine_check(gate.physics_of(["physics.solver_iterations=1", "physics.ls_iterations=1"]))
  assert all(c.ok for c in good) and good[0].value < 0.001 and good[1].value < 0.005  # MJX vs C, same options
  assert not any(c.ok for c in bad) and bad[0].value > 0.1  # m: the fall goes wrong


def test_flat_ground_oracles_pass_under_the_default_physics():
  checks = gate.flat_checks(gate.physics_of([]))
  assert [c.name for c in checks] == ["flat speed error", "flat lateral drift", "yaw rate error"]
  assert all(c.ok for c in checks), checks


def test_the_gate_takes_physics_settings_only(capsys):
  assert bench_main(["gate", "--set", "reward.cog_scale=1"]) == 2
  assert "physics settings only" in capsys.readouterr().err
  with pytest.raises(ValueError, match="solver_iterations"):
    gate.physics_of(["physics.solver_iterations=0"])

"""`--hp KEY=VALUE`: a preset's hyper-parameters changed per run, typed by the preset's own fields,
refused in one line naming the key, recorded in run.json, kept by --resume and passed by studies."""

import dataclasses
import os

import pytest

from train.core.plan import RunError, plan_run, write_run_json
from train.core.presets import get_preset, with_hyperparams
from train.run import parser as run_parser
from train.study.spec import cells, study_from_dict


def test_values_take_the_type_of_the_presets_field():
  p = with_hyperparams(get_preset("ppo", "gpu"), ["discounting=0.995", "policy_hidden=[64, 64]",
                                                  "run_evals=false", "unroll_length=10", "learning_rate=1e-3"])
  assert (p.discounting, p.policy_hidden, p.run_evals, p.unroll_length) == (0.995, (64, 64), False, 10)
  assert p.learning_rate == 1e-3 and isinstance(p.learning_rate, float)
  assert dataclasses.replace(p, discounting=0.97, policy_hidden=(128,) * 3, run_evals=True, unroll_length=20,
                             learning_rate=3e-4) == get_preset("ppo", "gpu")  # nothing else changed
  assert with_hyperparams(get_preset("sac", "paper"), ["tau=0.01"]).tau == 0.01


@pytest.mark.parametrize("item, words", [
    ("discounting=1.5", "--hp discounting: a number in [0, 1], got '1.5'"),
    ("discounting=high", "--hp discounting: a number in [0, 1]"),
    ("batch_size=0", "--hp batch_size: a whole number >= 1"),
    ("batch_size=2.5", "--hp batch_size: a whole number >= 1"),
    ("run_evals=2", "--hp run_evals: true or false"),
    ("learning_rate=.inf", "--hp learning_rate: a number > 0"),
    ("reward_scaling=0", "--hp reward_scaling: a number > 0"),
    ("policy_hidden=[0]", "--hp policy_hidden: a list of widths"),
    ("num_envs=8", "--hp num_envs: set it with --num-envs"),
    ("config_overrides=[]", "--hp config_overrides: set it with --set"),
    ("gamma=0.99", "--hp gamma: not a hyper-parameter of PPOPreset; known: unroll_length"),
    ("discounting", "--hp takes KEY=VALUE"),
])
def test_bad_items_are_refused_naming_the_key(item, words):
  with pytest.raises(ValueError) as e:
    with_hyperparams(get_preset("ppo", "gpu"), [item])
  assert words in str(e.value) and "\n" not in str(e.value)


def test_a_run_records_its_hyper_parameters_and_resume_keeps_them(tmp_path):
  out = str(tmp_path / "run")
  plan = plan_run(run_parser().parse_args(["--task", "asc-inc-cog", "--preset", "cpu", "--hp", "discounting=0.9",
                                           "--out", out]))
  assert plan.preset.discounting == 0.9 and plan.hp == ("discounting=0.9",)
  write_run_json(plan)
  os.makedirs(os.path.join(out, "checkpoints", "512"))  # a checkpoint short of the run's 2,560 steps
  again = plan_run(run_parser().parse_args(["--resume", out]))
  assert again.preset.discounting == 0.9 and again.hp == plan.hp and again.start_step == 512
  with pytest.raises(RunError, match="drop --hp"):
    plan_run(run_parser().parse_args(["--resume", out, "--hp", "discounting=0.5"]))
  with pytest.raises(RunError, match="--hp gae_lambda: a number in"):
    plan_run(run_parser().parse_args(["--task", "asc-inc-cog", "--preset", "cpu", "--hp", "gae_lambda=-1",
                                      "--out", str(tmp_path / "other")]))


def test_a_study_group_passes_its_hyper_parameters_to_its_runs(tmp_path):
  group = {"name": "g", "algo": "ppo", "preset": "cpu", "steps": [512], "hp": ["discounting=0.995"]}
  spec = study_from_dict({"name": "s", "tasks": ["asc-inc-cog"], "seeds": [0], "groups": [group]})
  cell = [c for c in cells(spec) if not c.is_baseline][0]
  plan = plan_run(run_parser().parse_args(cell.run_args(str(tmp_path / "run"), str(tmp_path / "db.sqlite"))))
  assert plan.preset.discounting == 0.995
  with pytest.raises(Exception, match=r"groups\[0\]: --hp discounting: a number in \[0, 1\]"):
    study_from_dict({"name": "s", "tasks": ["asc-inc-cog"], "seeds": [0], "groups": [{**group, "hp": ["discounting=2"]}]})

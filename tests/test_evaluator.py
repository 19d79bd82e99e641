"""The in-training evaluation on uniform scenes (Brax's evaluator, `[eval]` lines) of a preset that
has one: it runs on a fresh learner state and reports finite figures over its episodes. (The CPU
presets train without it, to keep the end-to-end tests short.)"""

import dataclasses

import numpy as np

from helpers import TINY
from train.core.build import build, init_state
from train.core.plan import plan_run
from train.run import parser
from train.core.session import evaluator_of


def test_a_preset_with_evaluations_evaluates_a_fresh_policy_on_uniform_scenes(tmp_path):
  plan = plan_run(parser().parse_args(["--task", "asc-inc-cog", "--algo", "sac", "--preset", "cpu", *TINY,
                                       "--out", str(tmp_path / "run")]))
  plan = dataclasses.replace(plan, preset=dataclasses.replace(plan.preset, num_evals=2, num_eval_envs=4))
  t = build(plan)
  metrics = evaluator_of(t)(init_state(t, 0))
  assert np.isfinite(metrics["eval/episode_reward"]) and metrics["eval/avg_episode_length"] > 0
  assert 0.0 <= metrics["eval/episode_progress"] <= 1.0 and 0.0 <= metrics["eval/episode_goal_reached"] <= 1.0

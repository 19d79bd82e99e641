"""The in-training evaluation on the hardest staircase: the very trials of `python -m train.evaluate
RUN --scene hardest` (same reset keys, deterministic policy), compiled once and run between
updates on the current parameters, so an early stop on its success is the final evaluation's."""

from __future__ import annotations

import jax
import numpy as np

from train.evaluate import EVAL_EPS, EVAL_TRIALS, per_trial_figures, scene_config, trial_keys, trial_rollout
from train.mesh import to_host

PREFIX = "hardest/"  # the probe's metrics: hardest/<report column>
COLUMNS = {"progress": "progress_mean", "success": "success_rate", "cog_deviation": "cog_deviation_mean",
           "pitch_rate": "pitch_rate_mean", "tipped_over": "tipped_rate"}  # per-trial figure -> report column


class HardestProbe:
  """probe(state) -> {hardest/<column>: mean over the trials} for a learner state."""

  def __init__(self, t, trials: int = EVAL_TRIALS):
    make_policy, policy_params = t.learner.make_policy, t.learner.policy_params
    key = jax.random.PRNGKey(0)  # unused by the deterministic policy

    def make_act(params):
      inference = make_policy(params, deterministic=True)
      return lambda obs: inference(obs, key)[0]

    _, rollout = trial_rollout(scene_config(t.plan.cfg, "hardest"), make_act, trials, EVAL_EPS)
    keys = trial_keys(trials)
    self.trials = trials
    self._run = jax.jit(lambda state: rollout(policy_params(state), keys)[0])

  def __call__(self, state) -> dict[str, float]:
    fig = per_trial_figures(to_host(self._run(state)))
    return {PREFIX + column: float(np.mean(fig[name])) for name, column in COLUMNS.items()}

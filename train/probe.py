"""The in-training evaluation on the hardest staircase: the very trials of `python -m train.evaluate
RUN --scene hardest` (same reset keys, deterministic policy), compiled once and run between
updates on the current parameters, so an early stop on its success is the final evaluation's."""

from __future__ import annotations

import jax
import numpy as np

from mjx_tracks.metrics import REPORT_COLUMN as COLUMNS  # per-trial figure -> report column
from train.evaluation import EVAL_EPS, EVAL_TRIALS, per_trial_figures, scene_config, trial_keys, trial_rollout
from train.mesh import to_host
from train.policy import act_from_params

PREFIX = "hardest/"  # the probe's metrics: hardest/<report column>


class HardestProbe:
  """probe(state) -> {hardest/<column>: mean over the trials} for a learner state."""

  def __init__(self, t, trials: int = EVAL_TRIALS):
    policy_params = t.learner.policy_params
    _, rollout = trial_rollout(scene_config(t.plan.cfg, "hardest"), act_from_params(t.spec), trials, EVAL_EPS)
    keys = trial_keys(trials)
    self._run = jax.jit(lambda state: rollout(policy_params(state), keys)[0])

  def __call__(self, state) -> dict[str, float]:
    fig = per_trial_figures(to_host(self._run(state)))
    return {PREFIX + column: float(np.mean(fig[name])) for name, column in COLUMNS.items()}

"""The in-training evaluation on the task's probe scene (SceneKind.probe_scene: the hardest staircase or
terrain; random areas for navigation): the very trials of `python -m train.evaluate RUN --scene
SCENE` (the same compiled program: same reset keys, deterministic policy), compiled
once and run between updates on the current parameters, so an early stop on its success is the
final evaluation's (and the evaluation finds the program in the persistent compilation cache)."""

from __future__ import annotations

import numpy as np

from mjx_tracks.metrics import REPORT_COLUMN as COLUMNS  # per-trial figure -> report column
from train.evaluation import EVAL_EPS, EVAL_SEED, EVAL_TRIALS, trial_runner
from train.core.mesh import to_host
from train.core.policy import act_from_params

PREFIX = "probe/"  # the probe's metrics: probe/<report column>


class Probe:
  """probe(state) -> {probe/<column>: mean over the trials} for a learner state."""

  def __init__(self, t, trials: int = EVAL_TRIALS):
    self._params = t.learner.policy_params
    self._scene = t.plan.cfg.scene.probe_scene
    self._run = trial_runner(t.plan.cfg, [self._scene], act_from_params(t.spec), trials, EVAL_EPS, EVAL_SEED)

  def __call__(self, state) -> dict[str, float]:
    fig, _, _ = self._run(to_host(self._params(state)), self._scene)
    return {PREFIX + column: float(np.mean(fig[name])) for name, column in COLUMNS.items()}

"""The in-training evaluation on the task's probe scene (SceneKind.probe_scene: the hardest staircase or
terrain; random areas for navigation): the very trials of `python -m train.evaluate RUN --scene
SCENE` (the same compiled program: same reset keys, deterministic policy), compiled
once and run between updates on the current parameters, so an early stop on its success is the
final evaluation's (and the evaluation finds the program in the persistent compilation cache).
GroupProbe, for the runs of one program, runs the same trials vmapped over the runs' policies (on
the CPU one policy after another: train.evaluation.vmapped_trials): the same trials in another
program, which may round a trial's physics differently."""

from __future__ import annotations

import numpy as np

from mjx_tracks.metrics import REPORT_COLUMN as COLUMNS  # per-trial figure -> report column
from train.evaluation import EVAL_EPS, EVAL_SEED, EVAL_TRIALS, group_trial_runner, trial_runner
from train.core.ahead import CompiledAhead
from train.core.group_loop import AllRuns
from train.core.mesh import to_host
from train.core.policy import act_from_params

PREFIX = "probe/"  # the probe's metrics: probe/<report column>


class Probe(CompiledAhead):
  """probe(state) -> {probe/<column>: mean over the trials} for a learner state."""

  def __init__(self, t, trials: int = EVAL_TRIALS):
    self._params = t.learner.policy_params
    self._scene = t.plan.cfg.scene.probe_scene
    self._run = trial_runner(t.plan.cfg, [self._scene], act_from_params(t.spec), trials, EVAL_EPS, EVAL_SEED)

  def __call__(self, state) -> dict[str, float]:
    self.ready()
    fig, _, _ = self._run(to_host(self._params(state)), self._scene)
    return means(fig)

  def ahead_job(self, state):
    params = to_host(self._params(state))
    return lambda: self._run.compile_for(params, self._scene)


def means(fig: dict) -> dict[str, float]:
  """{probe/<column>: mean over the trials} of per-trial figures."""
  return {PREFIX + column: float(np.mean(fig[name])) for name, column in COLUMNS.items()}


class GroupProbe(AllRuns):
  """The probe of every run of one program (train.run --seeds) in one rollout: the same trials,
  vmapped over the runs' policies, so probing n runs costs about one run's probe, not n;
  `member(i)` is run i's probe (train.core.group_loop.AllRuns)."""

  def __init__(self, t, trials: int = EVAL_TRIALS, configs: list | None = None):
    """configs: each run's task config where the runs' tasks differ (each probed on its own task's
    probe scene: train.evaluation.group_trial_runner)."""
    self._params = params = t.learner.policy_params
    self._run = run = group_trial_runner(t.plan.cfg, t.plan.cfg.scene.probe_scene, act_from_params(t.spec), trials,
                                         EVAL_EPS, EVAL_SEED, configs)
    super().__init__(lambda states: [means(fig) for fig in run(to_host(params(states)))])

  def ahead_job(self, states):
    params = to_host(self._params(states))
    return lambda: self._run.compile_for(params)

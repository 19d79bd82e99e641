"""Brax's evaluation of every run of one program (`train.run --seeds`) in one unroll: the episodes
`brax.training.acting.Evaluator` plays for each run (num_eval_envs episodes of uniform scenes,
deterministic policy, reset keys from the run's own key sequence, which starts at
train.core.build.eval_key(seed)), all runs' episodes in one batch, block i played by run i's
policy; each run gets the episode metrics Brax's evaluator would report for it (the timing
metrics, eval/epoch_eval_time, eval/sps, eval/walltime, are the program's). Only where the runs'
episodes do not share a statistic: with reward.normalize_penalties the eval env's penalty
normalizer learns from the whole batch, so a program's runs are then evaluated each by its own
evaluator (`evaluations_shared`)."""

from __future__ import annotations

import functools
import time

import jax
import jax.numpy as jnp
import numpy as np
from brax.envs.wrappers.training import EvalWrapper
from brax.training import acting

from mjx_tracks.envs.task_data import stacked, task_data
from mjx_tracks.envs.wrappers import batched_env
from train.core.build import Training, eval_config, eval_core, eval_env, eval_key
from train.core.group_loop import AllRuns
from train.core.mesh import to_host


def group_policy(make_policy, params, runs: int):
  """A policy for `runs` runs' episodes at once: observations in `runs` equal blocks, block i acted
  on by make_policy(run i's params) (params: a leading run axis)."""
  def block(x):
    return x.reshape((runs, -1) + x.shape[1:])

  def flat(x):
    return x.reshape((-1,) + x.shape[2:])

  def policy(obs, key):
    actions, extras = jax.vmap(lambda p, o: make_policy(p)(o, key))(params, jax.tree.map(block, obs))
    return flat(actions), jax.tree.map(flat, extras)
  return policy


def evaluations_shared(cfg) -> bool:
  """Whether the runs of a program may share one evaluation batch: no statistic learnt from the
  batch (the penalty normalizer, reward.normalize_penalties) then couples their episodes."""
  return not cfg.reward.normalize_penalties


def episode_metrics(eval_metrics, runs: int) -> list[dict[str, float]]:
  """Each run's eval/... metrics from the episodes' (block i: run i's), as Brax's evaluator
  aggregates one run's (acting.Evaluator.run_evaluation: means and stds over the episodes,
  '..._per_step' sums divided by the episode's length)."""
  steps = np.asarray(eval_metrics.episode_steps).reshape(runs, -1)
  sums = {k: np.asarray(v).reshape((runs, -1) + np.shape(v)[1:]) for k, v in eval_metrics.episode_metrics.items()}
  out = []
  for i in range(runs):
    lengths = np.maximum(steps[i], 1.0).astype(float)
    m = {}
    for fn, suffix in ((np.mean, ""), (np.std, "_std")):
      for name, v in sums.items():
        m[f"eval/episode_{name}{suffix}"] = fn(v[i] / lengths if name.endswith("per_step") else v[i])
    m["eval/avg_episode_length"], m["eval/std_episode_length"] = np.mean(steps[i]), np.std(steps[i])
    out.append(m)
  return out


def _unroll(t: Training, runs: int, episodes: int, length: int, make, configs: list | None):
  """unroll(params, unroll_keys) -> the episodes' eval metrics, block i run i's (see GroupEvaluator)."""
  def play(env, params, unroll_keys, n: int):
    resets = jax.vmap(lambda k: jax.random.split(k, episodes))(unroll_keys)  # each run's own, as Brax's
    first = env.reset(resets.reshape((n * episodes,) + resets.shape[2:]))
    # the policy is deterministic: the acting key (run 0's) is not read
    final, _ = acting.generate_unroll(env, first, group_policy(make, params, n), unroll_keys[0], length)
    return final.info["eval_metrics"]

  if configs is None:
    env = EvalWrapper(eval_env(t))
    return lambda params, unroll_keys: play(env, params, unroll_keys, runs)
  core = eval_core(t)
  tasks = stacked([task_data(eval_config(c), core.cfg) for c in configs])

  def each(params, unroll_key, task):  # one run's episodes on its own task's scenes
    one = jax.tree.map(lambda x: x[None], (params, unroll_key))  # a program of one run
    return play(EvalWrapper(batched_env(core.for_task(task))), *one, 1)

  def unroll(params, unroll_keys):
    metrics = jax.vmap(each)(params, unroll_keys, tasks)  # (runs, episodes, ...): as one batch's blocks
    return jax.tree.map(lambda x: x.reshape((-1,) + x.shape[2:]), metrics)
  return unroll


class GroupEvaluator(AllRuns):
  """evaluate(states with a leading run axis) -> each run's Brax evaluation metrics, one unroll for
  all; `member(i)`: run i's evaluation (train.core.group_loop.AllRuns)."""

  def __init__(self, t: Training, seeds: list[int], configs: list | None = None):
    """configs: each run's task config where the runs' tasks differ (mjx_tracks.envs.task_data:
    each run's episodes then come from its own task's uniform scenes, in an unroll of its own,
    vmapped over the runs)."""
    runs, episodes, length = len(seeds), t.plan.preset.num_eval_envs, t.plan.cfg.episode.max_steps
    make = functools.partial(t.learner.make_policy, deterministic=True)
    self._unroll, self._runs = jax.jit(_unroll(t, runs, episodes, length, make, configs)), runs
    self._keys = jnp.stack([eval_key(s) for s in seeds])
    self._steps, self._walltime = runs * episodes * length, 0.0  # the program's env steps per evaluation; s evaluating
    self._params = t.learner.policy_params
    super().__init__(self.evaluate)

  def ahead_job(self, states):
    params, unroll_keys = to_host(self._params(states)), jax.vmap(jax.random.split)(self._keys)[:, 1]
    return lambda: self._unroll.lower(params, unroll_keys).compile()

  def evaluate(self, states) -> list[dict[str, float]]:
    """Every run's evaluation of the states' policies (each run's key advances as Brax's does)."""
    split = jax.vmap(jax.random.split)(self._keys)
    self._keys, unroll_keys = split[:, 0], split[:, 1]
    t0 = time.time()
    metrics = jax.tree.map(np.asarray, self._unroll(to_host(self._params(states)), unroll_keys))
    seconds = time.time() - t0
    self._walltime += seconds
    shared = {"eval/epoch_eval_time": seconds, "eval/sps": self._steps / seconds, "eval/walltime": self._walltime}
    return [{**shared, **m} for m in episode_metrics(metrics, self._runs)]

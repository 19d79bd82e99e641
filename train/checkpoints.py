"""Run checkpoints (orbax) and the exported policy.

RUN/checkpoints/<step>/ holds `params` (the algorithm's parameters as a state dict: PPO
(normalizer, policy, value), SAC (normalizer, policy, q)) and `meta` (JSON: step, algorithm,
network spec, curriculum state, config). Orbax writes each step to a temporary directory and
renames it when complete, so a run killed mid-save leaves the previous checkpoint readable.
RUN/policy/ is the export: (normalizer, policy) parameters plus policy.json, loadable without the
trainer by `train.policy.load_policy`.
"""

from __future__ import annotations

import json
import os
from typing import Any

import jax
import numpy as np
import orbax.checkpoint as ocp
from flax import serialization

from train.networks import NetworkSpec

KEEP = 3  # checkpoints kept


def _plain(tree):
  return jax.tree_util.tree_map(np.asarray, serialization.to_state_dict(tree))


def checkpoint_dir(run_dir: str) -> str:
  """RUN/checkpoints: where a run's checkpoints live."""
  return os.path.join(os.path.abspath(run_dir), "checkpoints")


def saved_steps(run_dir: str) -> list[int]:
  """Steps of the run's complete checkpoints, ascending, read from disk without creating anything
  (orbax names a finished step's directory by the number alone)."""
  path = checkpoint_dir(run_dir)
  return sorted(int(d) for d in os.listdir(path) if d.isdigit()) if os.path.isdir(path) else []


class RunCheckpoints:
  """The checkpoint manager of one run directory."""

  def __init__(self, run_dir: str):
    self.dir = checkpoint_dir(run_dir)
    self.mgr = ocp.CheckpointManager(self.dir, options=ocp.CheckpointManagerOptions(max_to_keep=KEEP, create=True))

  def save(self, step: int, params, meta: dict[str, Any]) -> bool:
    """Saves a step; a step already on disk is kept as it is (returns False)."""
    if step in self.mgr.all_steps():
      return False
    self.mgr.save(step, args=ocp.args.Composite(params=ocp.args.StandardSave(_plain(params)),
                                                meta=ocp.args.JsonSave(dict(meta, step=step))), force=True)
    self.mgr.wait_until_finished()
    return True

  def latest_step(self) -> int | None:
    return self.mgr.latest_step()

  def restore(self, step: int | None = None) -> tuple[dict, dict]:
    """(raw params state dict, meta) of a step (default: latest)."""
    step = self.latest_step() if step is None else step
    if step is None:
      raise FileNotFoundError(f"no checkpoint in {self.dir}")
    out = self.mgr.restore(step, args=ocp.args.Composite(params=ocp.args.StandardRestore(),
                                                          meta=ocp.args.JsonRestore()))
    return out["params"], out["meta"]


def policy_params(raw: dict, spec: NetworkSpec):
  """(normalizer, policy) parameters from a checkpoint's raw state dict (either algorithm)."""
  return serialization.from_state_dict(spec.init_policy_params(), {"0": raw["0"], "1": raw["1"]})


def restore_ppo_params(raw: dict, spec: NetworkSpec):
  """Raw state dict -> (normalizer, policy, value) with brax's types, for ppo.train(restore_params=)."""
  nets = spec.build()
  normalizer, policy = spec.init_policy_params()
  value = nets.value_network.init(jax.random.PRNGKey(0))
  return serialization.from_state_dict((normalizer, policy, value), raw)


def export_policy(out_dir: str, normalizer, policy, spec: NetworkSpec, info: dict[str, Any]) -> str:
  """Writes RUN/policy/: parameters and policy.json; returns the directory."""
  path = os.path.join(os.path.abspath(out_dir), "policy")
  ckpt = ocp.StandardCheckpointer()
  ckpt.save(os.path.join(path, "params"), _plain((normalizer, policy)), force=True)
  ckpt.wait_until_finished()
  with open(os.path.join(path, "policy.json"), "w") as f:
    json.dump({"network": spec.to_json(), **info}, f, indent=1)
  return path

"""Load an exported policy into a jitted act(observation) -> action, without the trainer.

    from train.core.policy import load_policy
    act = load_policy("runs/my-run/policy")
    env = mjx_tracks.load("asc-inc-cog")
    state = env.reset(jax.random.PRNGKey(0))
    action = act(state.obs)            # deterministic, in [-1, 1]^k
"""

from __future__ import annotations

import json
import os

import jax
import orbax.checkpoint as ocp
from flax import serialization

from train.core.networks import NetworkSpec


def load_policy_info(path: str) -> dict:
  meta = os.path.join(path, "policy.json")
  if not os.path.exists(meta):
    raise FileNotFoundError(f"{path} is not an exported policy (no policy.json); "
                            "pass RUN_DIR/policy written by python -m train.run")
  with open(meta) as f:
    return json.load(f)


def load_policy(path: str, deterministic: bool = True):
  """A jitted function mapping an observation (or a batch) to an action."""
  spec, params = load_policy_params(path)
  return make_act(spec, params, deterministic)


def load_policy_params(path: str):
  """(network spec, (normalizer, policy) parameters) of an exported policy."""
  spec = NetworkSpec.from_json(load_policy_info(path)["network"])
  try:
    raw = ocp.StandardCheckpointer().restore(os.path.join(os.path.abspath(path), "params"))
  except Exception as e:  # orbax raises several types for missing / corrupt files
    raise ValueError(f"cannot read policy parameters in {path}: {e}") from e
  return spec, serialization.from_state_dict(spec.policy_params_target(), raw)


def act_from_params(spec: NetworkSpec, deterministic: bool = True):
  """make_act(params) -> act(observation): the parameters stay arguments of whatever jits it, so
  one compilation serves every checkpoint of a run."""
  inference = spec.make_inference_fn()
  key = jax.random.PRNGKey(0)  # ignored by the deterministic policy; a stochastic one samples with it every call
  # actions in [-1, 1] whatever the network's output (a "normal" PPO's mean is not squashed)
  return lambda params: (lambda obs: jax.numpy.clip(inference(params, deterministic=deterministic)(obs, key)[0], -1, 1))


def make_act(spec: NetworkSpec, params, deterministic: bool = True):
  """A jitted act(observation) from (normalizer, policy) parameters."""
  act = act_from_params(spec, deterministic)
  return jax.jit(lambda obs: act(params)(obs))


def load_checkpoint_params(run_dir: str, step: int | None = None):
  """(network spec, (normalizer, policy) parameters, step) of a training checkpoint (default: the
  latest), e.g. of a killed run; of the project's trainer or of Stable-Baselines3 (run.json's library)."""
  from train.core.checkpoints import RunCheckpoints, checkpoint_dir, policy_params, saved_steps  # noqa: PLC0415
  from train.core.presets import SB3  # noqa: PLC0415
  from train.core.run_record import read_run_record  # noqa: PLC0415
  steps = saved_steps(run_dir)
  if not steps:
    raise FileNotFoundError(f"no checkpoint in {checkpoint_dir(run_dir)} to evaluate")
  if step is not None and step not in steps:
    raise ValueError(f"no checkpoint {step} in {checkpoint_dir(run_dir)}; there are {steps}")
  step = steps[-1] if step is None else step
  try:
    record = read_run_record(run_dir, ("algo",))
  except FileNotFoundError:  # checkpoints alone, no run.json: the project's trainer's
    record = {}
  if record.get("library") == SB3:
    from train.core.sb3_trainer import checkpoint_policy  # noqa: PLC0415
    try:
      return (*checkpoint_policy(run_dir, record["algo"], step), step)
    except Exception as e:  # zip / torch readers raise several types for damaged files
      raise ValueError(f"cannot read checkpoint {step} in {checkpoint_dir(run_dir)}: {e}") from e
  ckpts = RunCheckpoints(run_dir)
  try:
    raw, meta = ckpts.restore(step)
  except Exception as e:  # orbax raises several types for missing or damaged files
    raise ValueError(f"cannot read checkpoint {step} in {ckpts.dir}: {e}") from e
  spec = NetworkSpec.from_json(meta["network"])
  return spec, policy_params(raw, spec), int(meta["step"])


def load_checkpoint_policy(run_dir: str, step: int | None = None, deterministic: bool = True):
  """(act, step) of a training checkpoint (default: the latest), e.g. of a killed run."""
  spec, params, step = load_checkpoint_params(run_dir, step)
  return make_act(spec, params, deterministic), step

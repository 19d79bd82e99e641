"""Load an exported policy into a jitted act(observation) -> action, without the trainer.

    from train.policy import load_policy
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

from train.networks import NetworkSpec


def load_policy_info(path: str) -> dict:
  meta = os.path.join(path, "policy.json")
  if not os.path.exists(meta):
    raise FileNotFoundError(f"{path} is not an exported policy (no policy.json); "
                            "pass RUN_DIR/policy written by python -m train.run")
  with open(meta) as f:
    return json.load(f)


def load_policy(path: str, deterministic: bool = True):
  """A jitted function mapping an observation (or a batch) to an action."""
  info = load_policy_info(path)
  spec = NetworkSpec.from_json(info["network"])
  try:
    raw = ocp.StandardCheckpointer().restore(os.path.join(os.path.abspath(path), "params"))
  except Exception as e:  # orbax raises several types for missing / corrupt files
    raise ValueError(f"cannot read policy parameters in {path}: {e}") from e
  params = serialization.from_state_dict(spec.init_policy_params(), raw)
  inference = spec.make_inference_fn()(params, deterministic=deterministic)
  key = jax.random.PRNGKey(0)
  return jax.jit(lambda obs: inference(obs, key)[0])

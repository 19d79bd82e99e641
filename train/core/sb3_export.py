"""An SB3 model's deterministic policy as the project's exported policy (NetworkSpec + Brax
parameters), so that train.evaluate, train.export (ONNX), studies and the dashboard use it as any
other run's.

The layers map one to one (torch's Linear weight is the transpose of flax's Dense kernel):
- SAC: actor.latent_pi (Linear, ReLU, ...) then actor.mu; the action is tanh(mu). Brax's SAC
  policy is the same ReLU MLP with a last layer of 2 x A outputs (mean, scale) and acts with
  tanh(mean): the mean half takes mu, the scale half (unused by a deterministic policy) is zero.
- TD3: actor.mu is (Linear, ReLU, ..., Linear, Tanh): the same tanh(last layer), so the same map.
- PPO: mlp_extractor.policy_net (Linear, Tanh, ...) then action_net, acting with the mean; Brax's
  PPO network with distribution "normal" and activation tanh: MLP_0 then Dense_0, std_param.
SB3 normalizes no observation: the spec says normalize_observations=False (an identity normalizer
is stored, as Brax's policies carry one).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from brax.training.acme import running_statistics, specs

from train.core.networks import NetworkSpec


def _linears(module) -> list:
  """The torch Linear layers of a module, in order."""
  import train.core.no_triton  # noqa: F401, PLC0415  (before PyTorch loads)
  import torch  # noqa: PLC0415
  return [m for m in module.modules() if isinstance(m, torch.nn.Linear)]


def _dense(linear) -> dict:
  return {"kernel": jnp.asarray(linear.weight.detach().cpu().numpy().T),
          "bias": jnp.asarray(linear.bias.detach().cpu().numpy())}


def _mlp(linears) -> dict:
  return {f"hidden_{i}": _dense(lin) for i, lin in enumerate(linears)}


def _tanh_actor(algo: str, model, spec: NetworkSpec) -> dict:
  """SAC / TD3: hidden layers + the mean, the scale half zero."""
  if algo == "sac":
    hidden, mu = _linears(model.actor.latent_pi), model.actor.mu
  else:
    *hidden, mu = _linears(model.actor.mu)
  layers = _mlp(hidden)
  last = _dense(mu)
  a = spec.action_size
  layers[f"hidden_{len(hidden)}"] = {"kernel": jnp.concatenate([last["kernel"], jnp.zeros_like(last["kernel"])], 1),
                                     "bias": jnp.concatenate([last["bias"], jnp.zeros((a,), last["bias"].dtype)])}
  return {"params": layers}


def _ppo_actor(model) -> dict:
  policy = model.policy
  std = np.exp(policy.log_std.detach().cpu().numpy())
  return {"params": {"MLP_0": _mlp(_linears(policy.mlp_extractor.policy_net)), "Dense_0": _dense(policy.action_net),
                     "std_param": {"value": jnp.asarray(std)}}}


def network_spec(algo: str, observation_size: int, action_size: int, hidden: tuple[int, ...]) -> NetworkSpec:
  """The spec of an SB3 policy of the given MLP widths (Brax's network of the same shape and output)."""
  if algo == "ppo":
    return NetworkSpec("ppo", observation_size, action_size, hidden, hidden, False, "tanh", "normal")
  return NetworkSpec("sac", observation_size, action_size, hidden, hidden, False, "relu")


def policy_params(algo: str, model, spec: NetworkSpec):
  """(normalizer, policy) parameters of the model's deterministic policy, in the spec's structure."""
  normalizer = running_statistics.init_state(specs.Array((spec.observation_size,), jnp.float32))
  policy = _ppo_actor(model) if algo == "ppo" else _tanh_actor(algo, model, spec)
  target = spec.policy_params_target()[1]
  if jax.tree_util.tree_structure(policy) != jax.tree_util.tree_structure(target):
    raise ValueError(f"the SB3 {algo} policy does not map onto the spec's network: {jax.tree_util.tree_structure(policy)}")
  return normalizer, jax.tree_util.tree_map(lambda x, t: jnp.asarray(x, t.dtype).reshape(t.shape), policy, target)

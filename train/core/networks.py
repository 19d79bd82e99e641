"""Network factories of the two algorithms, described by a small JSON-able spec."""

from __future__ import annotations

import dataclasses
import functools

import jax
from brax.training.acme import running_statistics, specs
from brax.training.agents.ppo import networks as ppo_networks
from brax.training.agents.sac import networks as sac_networks


@dataclasses.dataclass(frozen=True)
class NetworkSpec:
  algo: str  # "ppo" | "sac"
  observation_size: int
  action_size: int
  policy_hidden: tuple[int, ...]
  value_hidden: tuple[int, ...]  # PPO value / SAC Q network
  normalize_observations: bool = True

  def to_json(self) -> dict:
    return dataclasses.asdict(self)

  @staticmethod
  def from_json(d: dict) -> "NetworkSpec":
    return NetworkSpec(d["algo"], d["observation_size"], d["action_size"], tuple(d["policy_hidden"]),
                       tuple(d["value_hidden"]), d.get("normalize_observations", True))

  def factory(self):
    """The network_factory argument of brax's train()."""
    if self.algo == "ppo":
      return functools.partial(ppo_networks.make_ppo_networks,
                               policy_hidden_layer_sizes=self.policy_hidden,
                               value_hidden_layer_sizes=self.value_hidden)
    return functools.partial(sac_networks.make_sac_networks, hidden_layer_sizes=self.policy_hidden)

  def build(self):
    preprocess = running_statistics.normalize if self.normalize_observations else (lambda x, y: x)
    return self.factory()(self.observation_size, self.action_size, preprocess_observations_fn=preprocess)

  def init_policy_params(self):
    """(normalizer, policy) parameters with the right structure (targets for restoring)."""
    nets = self.build()
    normalizer = running_statistics.init_state(specs.Array((self.observation_size,), jax.numpy.float32))
    return normalizer, nets.policy_network.init(jax.random.PRNGKey(0))

  def make_inference_fn(self):
    nets = self.build()
    mod = ppo_networks if self.algo == "ppo" else sac_networks
    return mod.make_inference_fn(nets)

"""Network factories of the two algorithms, described by a small JSON-able spec."""

from __future__ import annotations

import dataclasses
import functools

import jax
from brax.training.acme import running_statistics, specs
from brax.training.agents.ppo import networks as ppo_networks
from brax.training.agents.sac import networks as sac_networks


ACTIVATIONS = {"relu": jax.nn.relu, "swish": jax.nn.swish, "tanh": jax.numpy.tanh}


@dataclasses.dataclass(frozen=True)
class NetworkSpec:
  algo: str  # "ppo" | "sac"
  observation_size: int
  action_size: int
  policy_hidden: tuple[int, ...]
  value_hidden: tuple[int, ...]  # PPO value / SAC Q network
  normalize_observations: bool = True
  activation: str = ""  # ACTIVATIONS; "": Brax's default of the family (PPO swish, SAC relu)
  distribution: str = "tanh_normal"  # PPO: "normal" acts with the mean as is (SB3's PPO; the env clips)

  def to_json(self) -> dict:
    return dataclasses.asdict(self)

  @staticmethod
  def from_json(d: dict) -> "NetworkSpec":
    return NetworkSpec(d["algo"], d["observation_size"], d["action_size"], tuple(d["policy_hidden"]),
                       tuple(d["value_hidden"]), d.get("normalize_observations", True), d.get("activation", ""),
                       d.get("distribution", "tanh_normal"))

  def factory(self):
    """The network_factory argument of brax's train()."""
    own = {"activation": ACTIVATIONS[self.activation]} if self.activation else {}
    if self.algo == "ppo":
      return functools.partial(ppo_networks.make_ppo_networks,
                               policy_hidden_layer_sizes=self.policy_hidden,
                               value_hidden_layer_sizes=self.value_hidden, distribution_type=self.distribution, **own)
    return functools.partial(sac_networks.make_sac_networks, hidden_layer_sizes=self.policy_hidden, **own)

  def build(self):
    preprocess = running_statistics.normalize if self.normalize_observations else (lambda x, y: x)
    return self.factory()(self.observation_size, self.action_size, preprocess_observations_fn=preprocess)

  def init_policy_params(self):
    """(normalizer, policy) parameters as a new network has them (computed: each of their small
    operations compiled on its first use in a process, ~1.5 s the first time on a 2-core CPU)."""
    nets = self.build()
    normalizer = running_statistics.init_state(specs.Array((self.observation_size,), jax.numpy.float32))
    return normalizer, nets.policy_network.init(jax.random.PRNGKey(0))

  def policy_params_target(self):
    """The structure, shapes and dtypes of init_policy_params (jax.ShapeDtypeStruct leaves), nothing
    computed or compiled: the target a restore fills (flax.serialization.from_state_dict)."""
    return jax.eval_shape(self.init_policy_params)

  def make_inference_fn(self):
    nets = self.build()
    mod = ppo_networks if self.algo == "ppo" else sac_networks
    return mod.make_inference_fn(nets)

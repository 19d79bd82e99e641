"""PPO from brax.training's parts (its loss, networks, acting, running statistics) with optax, as
one pure update: collect unrolls from every environment, then epochs of minibatch SGD."""

from __future__ import annotations

import dataclasses
import functools

import jax
import jax.numpy as jnp
import optax
from brax.envs.base import State
from brax.training import acting
from brax.training.acme import running_statistics, specs
from brax.training.agents.ppo import losses as ppo_losses
from brax.training.agents.ppo import networks as ppo_networks
from flax import struct

from train.core.algos.episodes import curriculum_figures, finished_sums
from train.core.presets import PPOPreset

STATE_EXTRAS = ("truncation", "episode_metrics", "episode_done")


@struct.dataclass
class PPOState:
  params: ppo_losses.PPONetworkParams
  opt_state: optax.OptState
  normalizer: running_statistics.RunningStatisticsState
  env_state: State  # the batch of environments, sharded over devices
  key: jax.Array


@dataclasses.dataclass(frozen=True)
class PPOLayout:
  """How one update is cut: `unrolls` unrolls of every environment, into minibatches."""
  num_envs: int
  unroll_length: int
  unrolls: int
  num_minibatches: int
  note: str | None = None  # what was adapted from the preset, if anything

  @property
  def steps_per_update(self) -> int:
    return self.num_envs * self.unroll_length * self.unrolls


def ppo_layout(p: PPOPreset, num_envs: int, devices: int) -> PPOLayout:
  """The preset's sequences per update (batch_size x num_minibatches) rounded up to whole unrolls
  of num_envs, and as many minibatches as divide them evenly over the devices."""
  want = p.batch_size * p.num_minibatches
  unrolls = max(1, -(-want // num_envs))
  per_device = unrolls * num_envs // devices
  minibatches = max(d for d in range(1, p.num_minibatches + 1) if per_device % d == 0)
  note = None
  if unrolls * num_envs != want or minibatches != p.num_minibatches:
    note = (f"{num_envs} envs: {unrolls * num_envs} sequences of {p.unroll_length} steps per update in "
            f"{minibatches} minibatches (preset: {want} in {p.num_minibatches})")
  return PPOLayout(num_envs, p.unroll_length, unrolls, minibatches, note)


def batch_major(data):
  """Transitions [unrolls, unroll_length, num_envs, ...] -> [unrolls * num_envs, unroll_length, ...]."""
  data = jax.tree_util.tree_map(lambda x: jnp.swapaxes(x, 1, 2), data)  # [U, B, T, ...]
  return jax.tree_util.tree_map(lambda x: x.reshape((-1,) + x.shape[2:]), data)


class PPO:
  """The learner: `init(key)` and the pure `update(state) -> (state, metrics)`."""

  def __init__(self, env, networks: ppo_networks.PPONetworks, p: PPOPreset, layout: PPOLayout,
               batch_sharding=None):
    self.env, self.nets, self.p, self.layout = env, networks, p, layout
    self.batch_sharding = batch_sharding  # keeps minibatches split over devices
    self.optimizer = optax.chain(optax.clip_by_global_norm(p.max_grad_norm), optax.adam(p.learning_rate))
    self.loss = functools.partial(
        ppo_losses.compute_ppo_loss, ppo_network=networks, entropy_cost=p.entropy_cost,
        discounting=p.discounting, reward_scaling=p.reward_scaling, gae_lambda=p.gae_lambda,
        clipping_epsilon=p.clipping_epsilon, normalize_advantage=True)
    self.make_policy = ppo_networks.make_inference_fn(networks)
    self.steps_per_update = layout.steps_per_update

  def init(self, key: jax.Array) -> PPOState:
    k_policy, k_value, k_env, k_next = jax.random.split(key, 4)
    params = ppo_losses.PPONetworkParams(self.nets.policy_network.init(k_policy),
                                         self.nets.value_network.init(k_value))
    normalizer = running_statistics.init_state(specs.Array((self.env.observation_size,), jnp.float32))
    env_state = self.env.reset(jax.random.split(k_env, self.layout.num_envs))
    return PPOState(params, self.optimizer.init(params), normalizer, env_state, k_next)

  def policy_params(self, s: PPOState):
    """(normalizer, policy): what the exported policy needs."""
    return s.normalizer, s.params.policy

  def update(self, s: PPOState):
    """One PPO iteration: unrolls, normalizer update, epochs of minibatch SGD."""
    k_sgd, k_unroll, k_next = self.keys(s.key)
    policy = self.make_policy(self.policy_params(s))
    env_state, data = self._collect(s.env_state, policy, k_unroll)
    return self.learn(s.replace(env_state=env_state), data, k_sgd, k_next)

  @staticmethod
  def keys(key: jax.Array):
    """(SGD key, unrolls' key, the next update's key) of an update from state key `key`."""
    return jax.random.split(key, 3)

  def learn(self, s: PPOState, data, k_sgd: jax.Array, k_next: jax.Array):
    """The update's second part, from its transitions data [unrolls * num_envs, unroll_length]:
    normalizer update, epochs of minibatch SGD; s holds the environments after the unrolls."""
    normalizer = running_statistics.update(s.normalizer, data.observation)
    epoch = functools.partial(self._epoch, data=data, normalizer=normalizer)
    (opt_state, params, _), losses = jax.lax.scan(
        epoch, (s.opt_state, s.params, k_sgd), (), length=self.p.num_updates_per_batch)
    metrics = {f"training/{k}": jnp.mean(v) for k, v in losses.items()}
    metrics.update(finished_sums(data.extras["state_extras"]), **curriculum_figures(s.env_state))
    return PPOState(params, opt_state, normalizer, s.env_state, k_next), metrics

  def _collect(self, env_state, policy, key):
    """`unrolls` unrolls of every environment -> transitions [unrolls * num_envs, unroll_length]."""
    def unroll(carry, _):
      state, k = carry
      k, k_next = jax.random.split(k)
      state, data = acting.generate_unroll(self.env, state, policy, k, self.layout.unroll_length,
                                           extra_fields=STATE_EXTRAS)
      return (state, k_next), data

    (env_state, _), data = jax.lax.scan(unroll, (env_state, key), (), length=self.layout.unrolls)
    return env_state, batch_major(data)

  def step_keys(self, key: jax.Array) -> jax.Array:
    """The policy's key at each env step of _collect's unrolls from unrolls' key `key`, in order
    ([unrolls * unroll_length] keys): the chains of its scan and of Brax's generate_unroll."""
    def chain(k, _):
      k, k_next = jax.random.split(k)
      return k_next, k

    _, per_unroll = jax.lax.scan(chain, key, (), length=self.layout.unrolls)
    per_step = jax.vmap(lambda k: jax.lax.scan(chain, k, (), length=self.layout.unroll_length)[1])(per_unroll)
    return per_step.reshape((-1,) + per_step.shape[2:])

  def _epoch(self, carry, _, data, normalizer):
    """One pass over the batch in shuffled minibatches."""
    opt_state, params, key = carry
    key, k_perm, k_grad = jax.random.split(key, 3)
    perm = jax.random.permutation(k_perm, data.reward.shape[0])
    m = self.layout.num_minibatches

    def minibatches(x):
      x = jnp.take(x, perm, axis=0).reshape((m, -1) + x.shape[1:])
      if self.batch_sharding is not None:
        x = jax.lax.with_sharding_constraint(x, self.batch_sharding)
      return x

    (opt_state, params, _), losses = jax.lax.scan(
        functools.partial(self._minibatch, normalizer=normalizer), (opt_state, params, k_grad),
        jax.tree_util.tree_map(minibatches, data))
    return (opt_state, params, key), losses

  def _minibatch(self, carry, data, normalizer):
    opt_state, params, key = carry
    key, k_loss = jax.random.split(key)
    (_, losses), grads = jax.value_and_grad(self.loss, has_aux=True)(params, normalizer, data, k_loss)
    updates, opt_state = self.optimizer.update(grads, opt_state)
    return (opt_state, optax.apply_updates(params, updates), key), losses

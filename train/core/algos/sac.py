"""SAC from brax.training's parts (its losses, networks, acting, replay buffer, running statistics)
with optax, as one pure update: actor steps into the replay buffer, then gradient steps."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import optax
from brax.envs.base import State
from brax.training import acting, gradients, replay_buffers
from brax.training.acme import running_statistics, specs
from brax.training.agents.sac import losses as sac_losses
from brax.training.agents.sac import networks as sac_networks
from brax.training.types import Params, Transition
from flax import struct

from train.core.algos.episodes import curriculum_figures, finished_sums
from train.core.algos.ppo import STATE_EXTRAS
from train.core.presets import SACPreset

ALPHA_LEARNING_RATE = 3e-4  # brax's SAC: a fixed Adam rate for log(alpha), which starts at 0


@struct.dataclass
class SACState:
  policy: Params
  q: Params
  target_q: Params
  log_alpha: jax.Array
  policy_opt: optax.OptState
  q_opt: optax.OptState
  alpha_opt: optax.OptState
  normalizer: running_statistics.RunningStatisticsState
  env_state: State  # the batch of environments, sharded over devices
  buffer: replay_buffers.ReplayBufferState  # the whole replay buffer, replicated
  key: jax.Array


def _stored(t: Transition) -> Transition:
  """What the buffer keeps of a transition (no episode bookkeeping)."""
  return t._replace(extras={"state_extras": {"truncation": t.extras["state_extras"]["truncation"]},
                            "policy_extras": {}})


def make_alpha_loss(networks: sac_networks.SACNetworks, target_entropy: float):
  """Brax's temperature loss (Haarnoja et al. 2018, eq. 18) toward `target_entropy` (nats), which
  brax fixes at -0.5 x the action size and Stable-Baselines3 at -1 x it (SACPreset.target_entropy)."""
  dist = networks.parametric_action_distribution

  def alpha_loss(log_alpha, policy_params, normalizer_params, transitions: Transition, key):
    params = networks.policy_network.apply(normalizer_params, policy_params, transitions.observation)
    log_prob = dist.log_prob(params, dist.sample_no_postprocessing(params, key))
    return jnp.mean(jnp.exp(log_alpha) * jax.lax.stop_gradient(-log_prob - target_entropy))
  return alpha_loss


class SAC:
  """The learner: `init(key)` and the pure `update(state) -> (state, metrics)`."""

  def __init__(self, env, networks: sac_networks.SACNetworks, p: SACPreset, num_envs: int):
    self.env, self.nets, self.p, self.num_envs = env, networks, p, num_envs
    self.steps_per_update = num_envs * p.actor_steps_per_update
    obs = jnp.zeros((env.observation_size,))
    dummy = Transition(obs, jnp.zeros((env.action_size,)), 0.0, 0.0, obs,
                       {"state_extras": {"truncation": 0.0}, "policy_extras": {}})
    self.buffer = replay_buffers.UniformSamplingQueue(p.max_replay_size, dummy,
                                                      p.batch_size * p.grad_updates_per_step)
    self.opt = {"policy": optax.adam(p.learning_rate), "q": optax.adam(p.learning_rate),
                "alpha": optax.adam(ALPHA_LEARNING_RATE)}
    _, critic_loss, actor_loss = sac_losses.make_losses(networks, p.reward_scaling, p.discounting, env.action_size)
    alpha_loss = make_alpha_loss(networks, p.target_entropy * env.action_size)
    self.alpha_update = gradients.gradient_update_fn(alpha_loss, self.opt["alpha"], pmap_axis_name=None)
    self.critic_update = gradients.gradient_update_fn(critic_loss, self.opt["q"], pmap_axis_name=None)
    self.actor_update = gradients.gradient_update_fn(actor_loss, self.opt["policy"], pmap_axis_name=None)
    self.make_policy = sac_networks.make_inference_fn(networks)

  def init(self, key: jax.Array) -> SACState:
    k_policy, k_q, k_env, k_buffer, k_next = jax.random.split(key, 5)
    policy, q = self.nets.policy_network.init(k_policy), self.nets.q_network.init(k_q)
    log_alpha = jnp.asarray(0.0, jnp.float32)
    normalizer = running_statistics.init_state(specs.Array((self.env.observation_size,), jnp.float32))
    env_state = self.env.reset(jax.random.split(k_env, self.num_envs))
    return SACState(policy, q, q, log_alpha, self.opt["policy"].init(policy), self.opt["q"].init(q),
                    self.opt["alpha"].init(log_alpha), normalizer, env_state, self.buffer.init(k_buffer), k_next)

  def policy_params(self, s: SACState):
    """(normalizer, policy): what the exported policy needs."""
    return s.normalizer, s.policy

  def update(self, s: SACState):
    """`actor_steps_per_update` times: one step of every environment into the buffer, then (once
    the buffer holds min_replay_size transitions) grad_updates_per_step gradient steps."""
    def step(carry, _):
      s, = carry
      k_act, k_sgd, k_next = jax.random.split(s.key, 3)
      s, sums = self._act(s.replace(key=k_next), k_act)
      ready = self.buffer.size(s.buffer) >= self.p.min_replay_size
      s, losses = jax.lax.cond(ready, self._train, self._skip, s, k_sgd)
      return (s,), {**sums, **losses}

    (s,), metrics = jax.lax.scan(step, (s,), (), length=self.p.actor_steps_per_update)
    sums = {k: jnp.sum(v) for k, v in metrics.items() if k.startswith("episode/")}
    losses = {k: jnp.mean(v) for k, v in metrics.items() if not k.startswith("episode/")}
    return s, {**sums, **losses, **curriculum_figures(s.env_state),
               "training/buffer_size": self.buffer.size(s.buffer)}

  def _act(self, s: SACState, key):
    policy = self.make_policy((s.normalizer, s.policy))
    env_state, t = acting.actor_step(self.env, s.env_state, policy, key, extra_fields=STATE_EXTRAS)
    normalizer = running_statistics.update(s.normalizer, t.observation)
    buffer = self.buffer.insert(s.buffer, _stored(t))
    return s.replace(env_state=env_state, normalizer=normalizer, buffer=buffer), \
        finished_sums(t.extras["state_extras"])

  def _skip(self, s: SACState, key):
    zero = jnp.zeros((), jnp.float32)
    return s, {"training/critic_loss": zero, "training/actor_loss": zero, "training/alpha_loss": zero,
               "training/alpha": jnp.exp(s.log_alpha)}

  def _train(self, s: SACState, key):
    buffer, batch = self.buffer.sample(s.buffer)
    batch = jax.tree_util.tree_map(lambda x: x.reshape((self.p.grad_updates_per_step, -1) + x.shape[1:]), batch)
    s, losses = jax.lax.scan(self._sgd_step, s.replace(buffer=buffer), (batch, jax.random.split(key, len(batch.reward))))
    return s, {k: jnp.mean(v) for k, v in losses.items()}

  def _sgd_step(self, s: SACState, batch_key):
    """Brax SAC's gradient step: alpha, critic, actor, then the Polyak-averaged target."""
    t, key = batch_key
    k_alpha, k_critic, k_actor = jax.random.split(key, 3)
    alpha_loss, log_alpha, alpha_opt = self.alpha_update(
        s.log_alpha, s.policy, s.normalizer, t, k_alpha, optimizer_state=s.alpha_opt)
    alpha = jnp.exp(s.log_alpha)  # as in brax: this step's losses use alpha before its update
    critic_loss, q, q_opt = self.critic_update(
        s.q, s.policy, s.normalizer, s.target_q, alpha, t, k_critic, optimizer_state=s.q_opt)
    actor_loss, policy, policy_opt = self.actor_update(
        s.policy, s.normalizer, q, alpha, t, k_actor, optimizer_state=s.policy_opt)
    target_q = jax.tree_util.tree_map(lambda a, b: a * (1 - self.p.tau) + b * self.p.tau, s.target_q, q)
    s = s.replace(policy=policy, q=q, target_q=target_q, log_alpha=log_alpha, policy_opt=policy_opt,
                  q_opt=q_opt, alpha_opt=alpha_opt)
    return s, {"training/critic_loss": critic_loss, "training/actor_loss": actor_loss,
               "training/alpha_loss": alpha_loss, "training/alpha": jnp.exp(log_alpha)}

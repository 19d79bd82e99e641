"""Presets of `train.run --library sb3`: Stable-Baselines3's SAC, TD3 and PPO, each field named as
SB3 names its constructor's argument (so `--hp gamma=0.995` reads as SB3's documentation), every
value SB3's default unless a comment says otherwise.

`paper` is the paper's regime: SB3's defaults, a 2 x 64 MLP, one robot, 20,000 control steps, and
for SAC an initial entropy coefficient of 0.5 (auto-tuned from there, as SB3's "auto_0.5") and
tau 0.05. The paper also sets "the entropy regularization coefficient to 0.05"; SB3's SAC has no
second entropy parameter (its coefficient starts at the initial value and is tuned toward the
target entropy -dim(A)), and the original framework's code passes tau=0.05 beside
ent_coef="auto_0.5": we read the paper's 0.05 as that tau, as the project's own `paper` preset
(train/core/presets.py) does.
"""

from __future__ import annotations

import dataclasses

ALGOS = ("sac", "td3", "ppo")


@dataclasses.dataclass(frozen=True)
class _Common:
  num_envs: int = 1  # robots stepped together (a VectorEnv of the task)
  num_timesteps: int = 20_000  # control steps of all robots together
  hidden: tuple[int, ...] = (64, 64)  # policy_kwargs.net_arch of the actor and the critic(s)
  learning_rate: float = 3e-4
  gamma: float = 0.99
  training_metrics_steps: int = 1_000  # steps between reports (database rows, TensorBoard, the status line)
  config_overrides: tuple[str, ...] = ()
  early_stop: str = ""  # none: SB3's runs have no early stop
  probe_steps: int = 0  # none: SB3's runs have no hardest-staircase probe


@dataclasses.dataclass(frozen=True)
class _OffPolicy(_Common):
  """What SB3's off-policy algorithms (SAC, TD3) share: a replay buffer and its update rhythm."""
  buffer_size: int = 1_000_000
  learning_starts: int = 100
  batch_size: int = 256
  tau: float = 0.005
  train_freq: int = 1  # steps of every robot between updates
  gradient_steps: int = 1


@dataclasses.dataclass(frozen=True)
class SACPreset(_OffPolicy):
  ent_coef_init: float = 0.5  # SB3's ent_coef="auto_<init>" (SB3's default is auto_1.0; the paper's 0.5)


@dataclasses.dataclass(frozen=True)
class TD3Preset(_OffPolicy):
  learning_rate: float = 1e-3
  policy_delay: int = 2
  action_noise: float = 0.1  # std of the Gaussian exploration noise (SB3: NormalActionNoise; none by default)


@dataclasses.dataclass(frozen=True)
class PPOPreset(_Common):
  n_steps: int = 2048  # steps of every robot per rollout
  batch_size: int = 64
  n_epochs: int = 10
  gae_lambda: float = 0.95
  clip_range: float = 0.2
  ent_coef: float = 0.0
  vf_coef: float = 0.5
  max_grad_norm: float = 0.5


PRESETS = {
    "sac": {"paper": SACPreset(tau=0.05),  # the original's tau (module docstring)
            "cpu": SACPreset(num_timesteps=2_000, hidden=(32, 32), batch_size=64, training_metrics_steps=250),
            "gpu": SACPreset(num_envs=64, num_timesteps=2_000_000, hidden=(256, 256), gradient_steps=8,
                             training_metrics_steps=20_000)},
    "td3": {"paper": TD3Preset(),
            "cpu": TD3Preset(num_timesteps=2_000, hidden=(32, 32), batch_size=64, training_metrics_steps=250),
            "gpu": TD3Preset(num_envs=64, num_timesteps=2_000_000, hidden=(256, 256), gradient_steps=8,
                             training_metrics_steps=20_000)},
    "ppo": {"paper": PPOPreset(),
            "cpu": PPOPreset(num_envs=4, num_timesteps=2_048, hidden=(32, 32), n_steps=128, batch_size=64,
                             n_epochs=2, training_metrics_steps=256),
            "gpu": PPOPreset(num_envs=256, num_timesteps=5_000_000, n_steps=64, batch_size=4096, n_epochs=5,
                             training_metrics_steps=50_000)},
}

# fields that are not SB3 constructor arguments (the run's own, or turned into one below)
OWN = {f.name for f in dataclasses.fields(_Common)} - {"learning_rate", "gamma"}


def model_kwargs(algo: str, preset) -> dict:
  """The SB3 constructor's keyword arguments of a preset (less env, policy, seed and device)."""
  kw = {k: v for k, v in dataclasses.asdict(preset).items() if k not in OWN}
  if algo == "sac":
    kw["ent_coef"] = f"auto_{kw.pop('ent_coef_init')}"
  if algo == "td3":
    kw.pop("action_noise")  # an object: made by the trainer, which knows the action size
  return kw

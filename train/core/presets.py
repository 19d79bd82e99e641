"""Training presets: `laptop`, the CPU default, which trains a policy that climbs the hardest
staircase of asc-inc-cog within 10 minutes on 2 cores; `cpu`, a small one for trying things and for
tests (seconds; its policies do not solve the task); tuned massively parallel ones for a GPU; and
the paper's SAC set-up (2 x 64 MLP, initial entropy coefficient 0.5, tau 0.05, gamma 0.99)."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import yaml


@dataclasses.dataclass(frozen=True)
class PPOPreset:
  num_envs: int = 4096
  num_timesteps: int = 20_000_000
  unroll_length: int = 20
  batch_size: int = 256
  num_minibatches: int = 16  # sequences per update: batch_size * num_minibatches (whole unrolls of num_envs)
  num_updates_per_batch: int = 4
  learning_rate: float = 3e-4
  entropy_cost: float = 1e-2
  discounting: float = 0.97
  gae_lambda: float = 0.95
  clipping_epsilon: float = 0.2
  reward_scaling: float = 10.0
  max_grad_norm: float = 1.0
  policy_hidden: tuple[int, ...] = (128, 128, 128)
  value_hidden: tuple[int, ...] = (256, 256, 256)
  num_evals: int = 10
  num_eval_envs: int = 256
  training_metrics_steps: int = 500_000
  probe_steps: int = 81_920  # steps between probes (train.core.probe) for the default episode length, longer ones in proportion
  #                             (train.core.plan.probe_interval); 0: none unless asked
  run_evals: bool = True  # brax's evaluation on a separate env (uniform scenes) at each eval point
  config_overrides: tuple[str, ...] = ("scene.curriculum.window=1024",)
  # train.run's --early-stop unless one is given (tasks with a hardest configuration): stop once solved
  early_stop: str = "success"


@dataclasses.dataclass(frozen=True)
class SACPreset:
  num_envs: int = 256
  num_timesteps: int = 5_000_000
  batch_size: int = 512
  learning_rate: float = 3e-4
  discounting: float = 0.99
  tau: float = 0.005
  reward_scaling: float = 10.0  # brax's SAC starts at alpha = 1; scaling rewards by s acts like alpha = 1/s
  target_entropy: float = -0.5  # nats per action dimension the temperature is tuned toward (brax's; SB3's: -1)
  grad_updates_per_step: int = 8
  actor_steps_per_update: int = 8  # steps of every environment per jitted update (then control returns)
  min_replay_size: int = 8192
  max_replay_size: int = 1_000_000
  hidden: tuple[int, ...] = (256, 256)
  training_metrics_steps: int = 100_000
  probe_steps: int = 100_000  # steps between probes for the default episode length, as PPOPreset's; 0: none unless asked
  num_evals: int = 10
  num_eval_envs: int = 256
  config_overrides: tuple[str, ...] = ("scene.curriculum.window=256",)
  early_stop: str = ""  # train.run's --early-stop unless one is given ("": none)


PRESETS: dict[str, dict[str, object]] = {
    "ppo": {
        "cpu": PPOPreset(num_envs=16, num_timesteps=2_560, unroll_length=8, batch_size=16,
                         num_minibatches=4, num_updates_per_batch=2, policy_hidden=(32, 32),
                         value_hidden=(32, 32), num_evals=2, num_eval_envs=8,
                         training_metrics_steps=512, probe_steps=0, run_evals=False, config_overrides=(),
                         early_stop=""),
        # the GPU preset's networks and update shape at 256 robots: 5,120 steps per update, 8 updates
        # (at ~115 steps/s on 2 cores: under 8 minutes with the compilation; results/first_run/)
        "laptop": PPOPreset(num_envs=256, num_timesteps=40_960, unroll_length=20, batch_size=64,
                            num_minibatches=4, num_updates_per_batch=4, num_evals=2, num_eval_envs=8,
                            training_metrics_steps=5_120, probe_steps=0, run_evals=False, config_overrides=(),
                            early_stop=""),
        "gpu": PPOPreset(),
    },
    "sac": {
        "cpu": SACPreset(num_envs=8, num_timesteps=1_024, batch_size=32, grad_updates_per_step=1, actor_steps_per_update=4,
                         min_replay_size=64, max_replay_size=10_000, hidden=(32, 32), num_evals=1,
                         training_metrics_steps=128, probe_steps=0,
                         num_eval_envs=8, config_overrides=()),
        "gpu": SACPreset(),
        # paper: SB3 SAC, 2 x 64 MLP, ent_coef init 0.5 (reward scale 2 with brax's alpha = 1),
        # tau 0.05, gamma 0.99, one robot, 20,000 control steps (brax's target entropy; the
        # paper-ablations study compares SB3's)
        "paper": SACPreset(num_envs=1, num_timesteps=20_000, batch_size=256, learning_rate=3e-4,
                           discounting=0.99, tau=0.05, reward_scaling=2.0, grad_updates_per_step=1,
                           actor_steps_per_update=50,
                           min_replay_size=100, max_replay_size=1_000_000, hidden=(64, 64),
                           training_metrics_steps=1_000, probe_steps=5_000,
                           num_evals=20, num_eval_envs=10, config_overrides=()),
    },
}


CPU_DEFAULT = {"ppo": "laptop", "sac": "cpu"}  # the preset a run on the CPU gets without --preset


SB3 = "sb3"  # the library whose presets are train/core/sb3_presets.py (the others train with these)


def presets_of(library: str | None = None) -> dict[str, dict[str, object]]:
  """{algo: {name: preset}} of a library's trainer (train.run --library)."""
  if library == SB3:
    from train.core import sb3_presets  # noqa: PLC0415
    return sb3_presets.PRESETS
  return PRESETS


def get_preset(algo: str, name: str, library: str | None = None):
  presets = presets_of(library)
  if algo not in presets:
    raise ValueError(f"unknown algorithm {algo!r}{f' for --library {library}' if library else ''}; known: {sorted(presets)}")
  if name not in presets[algo]:
    raise ValueError(f"unknown preset {name!r} for {algo}; known: {sorted(presets[algo])}")
  return presets[algo][name]


# fields --hp may not set: each has its own option, or is not a number
HP_ELSEWHERE = {"num_envs": "--num-envs", "num_timesteps": "--steps", "config_overrides": "--set",
                "early_stop": "--early-stop"}

HP_ZERO_OK = {"probe_steps"}  # whole-number fields where 0 means none; the others count from 1
HP_AT_MOST_ONE = {"discounting", "gae_lambda", "tau", "clipping_epsilon", "gamma", "clip_range"}
HP_POSITIVE = {"learning_rate", "reward_scaling", "max_grad_norm", "tau"}  # 0 would train nothing
HP_SIGNED = {"target_entropy"}  # any finite number (nats may be negative)


def with_hyperparams(preset, items: Sequence[str]):
  """The preset with KEY=VALUE items (`--hp`) replacing its fields, e.g. `discounting=0.995`,
  `policy_hidden=[64, 64]`; ValueError in one line naming the key."""
  changes = {}
  for item in items:
    key, sep, text = item.partition("=")
    key = key.strip()
    if not sep or not key:
      raise ValueError(f"--hp takes KEY=VALUE, e.g. discounting=0.995; got {item!r}")
    if key in HP_ELSEWHERE:
      raise ValueError(f"--hp {key}: set it with {HP_ELSEWHERE[key]}")
    names = [f.name for f in dataclasses.fields(preset) if f.name not in HP_ELSEWHERE]
    if key not in names:
      raise ValueError(f"--hp {key}: not a hyper-parameter of {type(preset).__name__}; known: {', '.join(names)}")
    changes[key] = _hp_value(key, text, getattr(preset, key))
  return dataclasses.replace(preset, **changes)


def _hp_value(key: str, text: str, default):
  """TEXT parsed as YAML and checked against the type of the field's DEFAULT."""
  try:
    value = yaml.safe_load(text)
    if isinstance(default, float) and isinstance(value, str):
      value = float(value)  # YAML 1.1 reads 1e-3 as text
  except (yaml.YAMLError, ValueError):
    value = None
  if isinstance(default, bool):
    ok = isinstance(value, bool)
  elif isinstance(default, int):
    ok = isinstance(value, int) and not isinstance(value, bool) and value >= (0 if key in HP_ZERO_OK else 1)
  elif isinstance(default, float):
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) \
        and _float_rule(key)[0](value)
    value = float(value) if ok else value
  else:  # layer widths
    ok = isinstance(value, list) and bool(value) and all(isinstance(v, int) and v > 0 for v in value)
    value = tuple(value) if ok else value
  if not ok:
    want = {bool: "true or false", int: f"a whole number >= {0 if key in HP_ZERO_OK else 1}",
            float: _float_rule(key)[1]}.get(type(default), "a list of widths, e.g. [64, 64]")
    raise ValueError(f"--hp {key}: {want}, got {text!r}")
  return value


def _float_rule(key: str):
  """(accepts(value), what it accepts in words) for a float field: HP_SIGNED any number,
  HP_POSITIVE > 0, the others >= 0; HP_AT_MOST_ONE also at most 1."""
  positive = key in HP_POSITIVE
  if key in HP_AT_MOST_ONE:
    return (lambda v: (v > 0 if positive else v >= 0) and v <= 1.0), f"a number in {'(' if positive else '['}0, 1]"
  if positive:
    return (lambda v: v > 0), "a number > 0"
  if key in HP_SIGNED:
    return (lambda v: True), "a number"
  return (lambda v: v >= 0), "a number >= 0"

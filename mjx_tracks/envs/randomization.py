"""Sim-to-real randomization: dynamics, actuation and sensors drawn per episode inside jit.

The `randomization` section of a task (defaults and ranges in configs/defaults.yaml) is off unless
`enabled` (the -robust tasks). An episode's draw is a `Perturbation`, data in the env state; each
field's distribution is in its comment. Every range is its hard end: with `grow`, a range widens
from the nominal robot (NOMINAL) to the whole range as the curriculum's eps goes from 0 to 1.

Where each draw acts:
  model (with_dynamics):    chassis mass and inertia, payload, centre of mass, contact friction of
                            everything but the belts, servo kp / kv, joint damping
  track model (mu_scale of Simulator.advance): the belts' friction along and across (mu_along, mu_across)
  control (belt_gains):     each side's belt speed gain
  substeps (TrackedRobotEnv._advance): action delay, control period jitter, pushes
  sensors (noisy_imu_and_joints, beams.depth_beams): IMU and joint noise and bias; depth range
                            noise, hidden rays and camera pitch
Noise levels are data in the Perturbation too: one compiled program runs any mix of perturbations
(TrackedRobotEnv(every_path=True), the robustness suite's batch of cases).
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
from flax import struct

from mjx_tracks.bounds import bound

Range = tuple[float, float]


@dataclasses.dataclass(frozen=True)
class RandomizationConfig:
  """The `randomization` section; each key's meaning and unit in configs/defaults.yaml."""

  enabled: bool
  friction_along: Range  # x, ~ U(min, max)
  friction_across: Range  # x
  mass: Range  # x, chassis mass and inertia
  payload: Range  # kg, added to the chassis
  com_offset: tuple[float, float, float]  # m, half-widths along the chassis' x, y, z
  belt_gain: Range  # x, each side apart
  servo_gain: Range  # x, kp and kv
  joint_damping: Range  # N m s / rad, added
  push_velocity: float = dataclasses.field(metadata=bound(0.0, 5.0))  # m/s
  push_interval: float = dataclasses.field(metadata=bound(0.25))  # s, mean time between pushes
  action_delay: tuple[int, int]  # physics substeps ~ U{min..max}
  period_jitter: int = dataclasses.field(metadata=bound(0, 100))  # substeps a: U{-a..a} added to a period
  imu_noise: tuple[float, float, float]  # std: roll / pitch rad, angular velocity rad/s, velocity m/s
  imu_bias: tuple[float, float]  # half-widths: roll / pitch rad, angular velocity rad/s
  joint_noise: float = dataclasses.field(metadata=bound(0.0, 0.5))  # rad, std
  joint_bias: float = dataclasses.field(metadata=bound(0.0, 0.5))  # rad, half-width
  depth_noise: float = dataclasses.field(metadata=bound(0.0, 0.5))  # std of the relative range error
  camera_pitch: Range  # rad, ~ U(min, max), > 0 tilts the camera down
  grow: bool  # ranges widen with the curriculum's eps

  def validate(self, key: str) -> None:
    from mjx_tracks.envs.config import require  # noqa: PLC0415  (config imports this module)
    for name, (lo, hi) in LIMITS.items():
      r = getattr(self, name)
      require(lo <= r[0] <= r[1] <= hi, f"{key}.{name}", f"needs {lo} <= min <= max <= {hi}, got {list(r)}")
    require(all(0.0 <= a <= 0.2 for a in self.com_offset), f"{key}.com_offset", "each from 0 to 0.2 m")
    require(all(0.0 <= a <= 1.0 for a in self.imu_noise), f"{key}.imu_noise", "each std from 0 to 1")
    require(all(0.0 <= a <= 0.5 for a in self.imu_bias), f"{key}.imu_bias", "each from 0 to 0.5")

  def acts(self, group: str) -> bool:
    """Whether any key of a group (GROUPS) departs from the nominal robot (static: a task without
    randomization compiles the paper's step)."""
    return self.enabled and any(getattr(self, k) != NOMINAL[k] for k in GROUPS[group])


# the nominal robot: every key's value that changes nothing (a fact of each key's meaning, not a default)
NOMINAL = {"friction_along": (1.0, 1.0), "friction_across": (1.0, 1.0), "mass": (1.0, 1.0),
           "payload": (0.0, 0.0), "com_offset": (0.0, 0.0, 0.0), "belt_gain": (1.0, 1.0),
           "servo_gain": (1.0, 1.0), "joint_damping": (0.0, 0.0), "push_velocity": 0.0,
           "action_delay": (0, 0), "period_jitter": 0, "imu_noise": (0.0, 0.0, 0.0),
           "imu_bias": (0.0, 0.0), "joint_noise": 0.0, "joint_bias": 0.0, "depth_noise": 0.0,
           "camera_pitch": (0.0, 0.0)}


PERIOD = "period"  # in action_delay's YAML: one control period of the task, in substeps (control.period / physics.timestep)


def resolve_period(section: dict, substeps: int) -> dict:
  """A randomization section (plain mapping) with PERIOD in action_delay read as the task's control
  period in substeps, so that a range or a robustness case follows any task's period."""
  delay = section.get("action_delay") if isinstance(section, dict) else None
  if not isinstance(delay, (list, tuple)) or PERIOD not in delay:
    return section
  return {**section, "action_delay": [substeps if d == PERIOD else d for d in delay]}


def nominal_section(section: dict) -> dict:
  """A randomization section (plain mapping) as the nominal robot: every NOMINAL key at its value,
  enabled, grow off (a robustness case's starting point)."""
  return {**section, **{k: list(v) if isinstance(v, tuple) else v for k, v in NOMINAL.items()},
          "enabled": True, "grow": False}


# [min, max] keys: what their ends may be
LIMITS = {"friction_along": (0.1, 3.0), "friction_across": (0.1, 3.0), "mass": (0.5, 2.0),
          "payload": (0.0, 20.0), "belt_gain": (0.5, 1.5), "servo_gain": (0.1, 3.0),
          "joint_damping": (0.0, 50.0), "action_delay": (0, 100), "camera_pitch": (-0.35, 0.35)}
# the costly paths of the step, compiled only where a key of theirs departs from NOMINAL (acts);
# the other draws (gains, belt friction, sensor noise) cost little and act whenever randomization is on
GROUPS = {"model": ("friction_along", "mass", "payload", "com_offset", "servo_gain", "joint_damping"),
          "timing": ("action_delay", "period_jitter"),
          "push": ("push_velocity",)}


@struct.dataclass
class Perturbation:
  """One episode's draw (each ~ U over its key's range, widened by eps with `grow`) and noise levels
  (data too, so that one program runs any mix of them: the robustness suite)."""

  friction: jax.Array  # (2,) x, belts along / across; along also scales every other contact's sliding friction
  mass: jax.Array  # () x, chassis mass and inertia
  payload: jax.Array  # () kg, added to the chassis at its centre of mass
  com_offset: jax.Array  # (3,) m, chassis centre of mass moved along its x, y, z, each ~ U(-a, a)
  belt_gain: jax.Array  # (2,) x, left and right side's belt speeds, each drawn apart
  servo_gain: jax.Array  # () x, servo kp and kv
  joint_damping: jax.Array  # () N m s / rad, added to every flipper / arm joint
  delay: jax.Array  # () int32 substeps the command arrives late, ~ U{min..max}
  period_jitter: jax.Array  # () int32 substeps a: each period lasts U{-a..a} substeps more (or less)
  push_velocity: jax.Array  # () m/s of a push
  push_probability: jax.Array  # () per control step: period / push_interval
  imu_bias: jax.Array  # (5,) roll, pitch (rad) and angular velocity (rad/s) biases, each ~ U(-a, a)
  imu_noise: jax.Array  # (3,) std: roll / pitch rad, angular velocity rad/s, linear velocity m/s
  joint_bias: jax.Array  # (n_joints,) rad, each ~ U(-a, a)
  joint_noise: jax.Array  # () rad, std
  depth_noise: jax.Array  # () std of each ray's relative range error
  hidden: jax.Array  # () probability that a ray is hidden (observation.noise)
  camera_pitch: jax.Array  # () rad, ~ U(min, max)


def perturbation_key(rng: jax.Array) -> jax.Array:
  """The key of an episode's draw from its reset key: apart from the three reset splits into
  (scene, observation, step) keys (split(rng, 3)[i] is fold_in(rng, i) under threefry's
  partitionable mode, so 3 is a fourth stream), the same for training resets and evaluation."""
  return jax.random.fold_in(rng, 3)


def _widen(r, nominal, g):
  """The range r pulled toward its nominal value: g = 1 the whole range, g = 0 the nominal."""
  return tuple(n + g * (x - n) for x, n in zip(r, nominal))


def draw(c: RandomizationConfig, key: jax.Array, eps: jax.Array, n_joints: int, hidden: float,
         period: float) -> Perturbation:
  """One episode's Perturbation (pure; the nominal robot where c is off): hidden, the task's
  observation.noise; period, its control period (s)."""
  g = jnp.clip(jnp.asarray(eps, jnp.float32), 0.0, 1.0) if c.grow else 1.0
  on = float(c.enabled)
  ks = iter(jax.random.split(key, 13))  # one per draw below

  def u(name, shape=()):  # ~ U(min, max) of a [min, max] key
    lo, hi = _widen(getattr(c, name), NOMINAL[name], g * on)
    return jax.random.uniform(next(ks), shape, minval=lo, maxval=hi)

  def sym(a, shape=()):  # ~ U(-a, a) of a half-width
    a = jnp.asarray(a, jnp.float32) * g * on
    return jax.random.uniform(next(ks), shape + a.shape, minval=-1.0, maxval=1.0) * a

  f = lambda x: jnp.asarray(x, jnp.float32) * g * on  # a noise level, as grown
  lo, hi = _widen(c.action_delay, NOMINAL["action_delay"], g * on)
  delay = jax.random.randint(next(ks), (), jnp.round(lo).astype(jnp.int32), jnp.round(hi).astype(jnp.int32) + 1)
  rate_bias = sym(c.imu_bias[1], (3,))
  return Perturbation(
      friction=jnp.stack([u("friction_along"), u("friction_across")]), mass=u("mass"), payload=u("payload"),
      com_offset=sym(c.com_offset), belt_gain=u("belt_gain", (2,)), servo_gain=u("servo_gain"),
      joint_damping=u("joint_damping"), delay=delay,
      period_jitter=jnp.round(f(c.period_jitter)).astype(jnp.int32), push_velocity=f(c.push_velocity),
      push_probability=jnp.float32(on * period / c.push_interval),
      imu_bias=jnp.concatenate([sym(c.imu_bias[0], (2,)), rate_bias]), imu_noise=f(c.imu_noise),
      joint_bias=sym(c.joint_bias, (n_joints,)), joint_noise=f(c.joint_noise), depth_noise=f(c.depth_noise),
      hidden=jnp.float32(hidden), camera_pitch=u("camera_pitch"))


def task_draw(cfg, rng: jax.Array, eps: jax.Array, n_joints: int) -> Perturbation:
  """The episode's draw of a task config's randomization from the episode's reset key (its own
  stream, perturbation_key): what TrackedRobotEnv.reset_at draws, and the robustness suite per case."""
  return draw(cfg.randomization, perturbation_key(rng), eps, n_joints, cfg.observation.noise, cfg.control.period)


@struct.dataclass
class RobustState:
  """What a randomized env carries beside the paper's state (EnvState.robust; None without randomization)."""

  perturbation: Perturbation
  belts: jax.Array  # (n_belts,) m/s, the last command's belt speeds: they act while a new command is late


def with_dynamics(m, p: Perturbation, chassis_body: int, joint_dofs) -> "mjx.Model":  # noqa: F821
  """The model with one episode's dynamics. The solver's compiled regularization (invweight0) is
  kept, as MuJoCo keeps it when a model's masses change at run time."""
  b = chassis_body
  mass0 = m.body_mass[b]
  mass = mass0 * p.mass + p.payload  # kg; the payload spread as the chassis' own mass
  dofs = jnp.asarray(joint_dofs)
  return m.replace(
      body_mass=m.body_mass.at[b].set(mass),
      body_inertia=m.body_inertia.at[b].multiply(mass / mass0),
      body_ipos=m.body_ipos.at[b].add(p.com_offset),
      geom_friction=m.geom_friction.at[:, 0].multiply(p.friction[0]),
      actuator_gainprm=m.actuator_gainprm.at[:, 0].multiply(p.servo_gain),
      actuator_biasprm=m.actuator_biasprm.at[:, 1:3].multiply(p.servo_gain),
      dof_damping=m.dof_damping.at[dofs].add(p.joint_damping))


def belt_gains(p: Perturbation, belt_side) -> jax.Array:
  """(n_belts,) each belt's speed gain: its side's (belt_side +1 left, -1 right)."""
  return jnp.where(jnp.asarray(belt_side) > 0, p.belt_gain[0], p.belt_gain[1])


def push(qvel: jax.Array, p: Perturbation, key: jax.Array) -> tuple[jax.Array, jax.Array]:
  """(qvel, pushed): with probability p.push_probability, p.push_velocity (m/s) added to the
  chassis' horizontal velocity in a direction ~ U(0, 2 pi)."""
  k_when, k_dir = jax.random.split(key)
  pushed = jax.random.uniform(k_when) < p.push_probability
  angle = jax.random.uniform(k_dir, minval=0.0, maxval=2 * jnp.pi)
  kick = p.push_velocity * jnp.stack([jnp.cos(angle), jnp.sin(angle)]) * pushed
  return qvel.at[0:2].add(kick), pushed


def period_substeps(p: Perturbation, substeps: int, key: jax.Array) -> jax.Array:
  """This control step's substeps: substeps + U{-a..a} (a: p.period_jitter), at least 1."""
  return jnp.maximum(substeps + jax.random.randint(key, (), -p.period_jitter, p.period_jitter + 1), 1)


def noisy_imu_and_joints(p: Perturbation, rpy, rate, velocity, joints, key):
  """(rpy, angular velocity, linear velocity, joints) as the sensors read them: roll / pitch +
  bias + N(0, imu_noise[0]) rad, rates + bias + N(0, imu_noise[1]) rad/s, velocity +
  N(0, imu_noise[2]) m/s, joints + bias + N(0, joint_noise) rad (yaw stays: the goal bearing is
  the localization's, not the IMU's)."""
  k = jax.random.split(key, 4)
  rpy = rpy.at[:2].add(p.imu_bias[:2] + p.imu_noise[0] * jax.random.normal(k[0], (2,)))
  rate = rate + p.imu_bias[2:] + p.imu_noise[1] * jax.random.normal(k[1], (3,))
  velocity = velocity + p.imu_noise[2] * jax.random.normal(k[2], (3,))
  joints = joints + p.joint_bias + p.joint_noise * jax.random.normal(k[3], joints.shape)
  return rpy, rate, velocity, joints

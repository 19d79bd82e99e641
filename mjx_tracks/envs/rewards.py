"""Rewards and termination (the paper's monitor, Section 4.3): reward terms, termination, success
and safety figures, all pure JAX.

Progress (the original's "closest distance so far" rule): dist = distance from p to the goal
(a point, or for stairs a segment across the staircase: goal +- halfwidth along y) - tolerance;
whenever dist falls below the closest distance so far, the robot earns (closest - max(dist, 0)) / d0,
d0 the starting dist; an episode's progress rewards sum to at most 1 (the fraction of d0 covered).
COG deviation (ascent, while on the stairs): with r the centre of mass relative to the chassis
origin, expressed in a frame tilted by the stair incline theta = atan(h / l) (x' along the incline,
z' normal to it), Cx = x' - tan|theta| z' and deviation = sqrt(z'^2 + Cx^2), clipped to [0, 0.32] m.
Angular (descent): |pitch angular velocity| (rad/s) of the chassis.
Safety penalty (reward.safety_form): `window`, the paper's, scale * K * mean of the last
`safety_window` safety samples per step (its episode sum grows with the episode's length, so a
policy that hurries pays less); `episode_mean`, scale * K * (M_t - M_{t-1}) with M_t the mean of the
episode's first t samples, whose sum over an episode is scale * K * the episode's mean sample: the
very figure evaluation reports, whatever the episode's length. K = 1, or with normalize_penalties
the original's K = 1 / mean per-episode penalty sum of the first N episodes (no penalty during those N).
Progress (reward.progress_form potential): (previous dist - dist) / d0 every step, negative when the
robot moves away: potential-based shaping, whose episode sum (d0 - final dist) / d0 is the same
for every path, so a detour costs nothing once undone. With episode.distance geodesic, dist is the
free-space path length around obstacles (scenes.geodesic) instead of the straight line.
Collision: a step whose physics touched a wall or obstacle costs collision_penalty and, with
episode.end_on_collision, ends the episode.
Clearance: with the robot's footprint c m from the nearest wall or wall obstacle (scenes.clearance),
a step costs clearance_penalty * max(clearance_margin - c, 0) / clearance_margin (at most
clearance_penalty, touching): room to turn before a collision, not only the collision.
Riding: a step that ends with a track belt on a floor obstacle (nav; mjx_tracks.sim.collisions)
costs riding_penalty: going round rather than over (results/nav/README.md: the zigzag's
collisions come with its floor obstacles).
Goal: reaching the goal earns goal_bonus once (it ends the episode): with a length-neutral safety
penalty, the only thing that makes running out of time cost more than the last metres of progress.
Tip-over: |roll| or |pitch| > pi/2 costs tipover_penalty and ends the episode. The episode also
ends when the goal is reached (dist < 0) or the robot moved away (dist > away_factor * d0).
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
from flax import struct

from mjx_tracks.envs.config import REWARD_SIGNALS, EpisodeConfig, RewardConfig
from mjx_tracks.sim.pose import tipped_over

COG_MAX = 0.32  # m
ON_STAIRS_MARGIN = 0.3  # m: "on the stairs" spans x in [-margin, top edge + margin] (chassis origin)
from mjx_tracks.metrics import REWARD_TERMS  # noqa: F401  (its named terms; Monitor.evaluate makes them)


def goal_distance(pos: jax.Array, goal: jax.Array, halfwidth: jax.Array, tolerance: float) -> jax.Array:
  """Distance (m) from p to the goal segment goal +- halfwidth along y, minus tolerance."""
  d = pos - goal
  d = d.at[..., 1].set(jnp.maximum(jnp.abs(d[..., 1]) - halfwidth, 0.0))
  return jnp.linalg.norm(d, axis=-1) - tolerance


def goal_reached(dist: jax.Array) -> jax.Array:
  """Success: the robot is within the tolerance of the goal (dist from goal_distance < 0)."""
  return dist < 0.0


def progress_step(dist: jax.Array, closest: jax.Array, d0: jax.Array,
                  form: str = "closest") -> tuple[jax.Array, jax.Array]:
  """(progress reward, new reference distance); distances below 0 (goal reached) count as 0.
  closest: the closest distance so far, or (form potential) the previous step's distance."""
  dist = jnp.maximum(dist, 0.0)
  if form == "potential":
    return (closest - dist) / jnp.maximum(d0, 1e-6), dist
  gain = jnp.maximum(closest - dist, 0.0) / jnp.maximum(d0, 1e-6)
  return gain, jnp.minimum(closest, dist)


def on_stairs(x: jax.Array, top_edge_x: jax.Array) -> jax.Array:
  """Whether the chassis origin's x (m) lies over the staircase (the COG deviation counts there)."""
  return (x >= -ON_STAIRS_MARGIN) & (x <= top_edge_x + ON_STAIRS_MARGIN)


def cog_deviation(com: jax.Array, chassis_pos: jax.Array, incline: jax.Array) -> jax.Array:
  """COG deviation (m) in the incline frame, clipped to [0, 0.32]."""
  r = com - chassis_pos
  c, s = jnp.cos(incline), jnp.sin(incline)
  x_p = r[0] * c + r[2] * s
  z_p = -r[0] * s + r[2] * c
  cx = x_p - jnp.tan(jnp.abs(incline)) * z_p
  return jnp.clip(jnp.sqrt(z_p**2 + cx**2), 0.0, COG_MAX)


@struct.dataclass
class PenaltyNormalizer:
  """Global K of the original's penalty normalization (same on every environment and device)."""

  k: jax.Array  # () current K (0 while calibrating)
  total: jax.Array  # () sum of per-episode penalty sums seen while calibrating
  count: jax.Array  # () int32 episodes seen while calibrating


def normalizer_init(cfg: RewardConfig) -> PenaltyNormalizer:
  k = jnp.float32(0.0 if cfg.normalize_penalties else 1.0)
  return PenaltyNormalizer(k, jnp.float32(0.0), jnp.int32(0))


def normalizer_update(cfg: RewardConfig, s: PenaltyNormalizer, done: jax.Array,
                      penalty_sums: jax.Array) -> PenaltyNormalizer:
  """Counts finished episodes' raw penalty sums until N are seen, then fixes K = 1 / mean."""
  if not cfg.normalize_penalties:
    return s
  need = cfg.normalize_episodes
  calibrating = s.count < need
  rank = jnp.cumsum(done) - 1
  take = done & (s.count + rank < need) & calibrating
  total = s.total + jnp.sum(jnp.where(take, penalty_sums, 0.0))
  count = s.count + jnp.sum(take).astype(jnp.int32)
  k = jnp.where(count >= need, need / jnp.maximum(total, 1e-6), 0.0)
  return PenaltyNormalizer(k.astype(jnp.float32), total, count)


@struct.dataclass
class Safety:
  """A reward kind's safety term as data (runs of several reward kinds in one program): which raw
  figure it penalizes (config.REWARD_SIGNALS) and its scale."""
  cog: jax.Array  # () bool: the COG deviation
  pitch: jax.Array  # () bool: the pitch rate (neither: no safety term)
  scale: jax.Array  # () float32: reward.cog_scale (1/m) or reward.angular_scale (s/rad); 0 where none


def safety_of(reward: RewardConfig) -> Safety:
  """reward's safety term (Monitor.safety_sample and safety_scale of its kind) as data."""
  signal = REWARD_SIGNALS[reward.kind]
  return Safety(jnp.bool_(signal == "cog_deviation"), jnp.bool_(signal == "pitch_rate"),
                jnp.float32(Monitor(reward, None).safety_scale()))


@dataclasses.dataclass(frozen=True)
class Monitor:
  """Reward and termination settings of one task; safety: its safety term as data (a program's
  runs of several reward kinds, mjx_tracks.envs.task_data), else the reward kind's."""

  reward: RewardConfig
  episode: EpisodeConfig
  safety: Safety | None = None

  def safety_sample(self, cog_dev: jax.Array, pitch_rate: jax.Array) -> jax.Array:
    """The raw safety figure the task's reward kind penalizes (config.REWARD_SIGNALS)."""
    if self.safety is not None:
      return jnp.where(self.safety.cog, cog_dev, jnp.where(self.safety.pitch, pitch_rate, 0.0))
    signal = REWARD_SIGNALS[self.reward.kind]
    return jnp.zeros_like(cog_dev) if signal is None else {"cog_deviation": cog_dev, "pitch_rate": pitch_rate}[signal]

  def safety_scale(self) -> float | jax.Array:
    if self.safety is not None:
      return self.safety.scale
    return {"cog": self.reward.cog_scale, "angular": self.reward.angular_scale}.get(self.reward.kind, 0.0)

  def safety_rate(self, window: jax.Array, signal_sum: jax.Array, steps: jax.Array) -> jax.Array:
    """This step's safety quantity before scale and K (reward.safety_form): the window's mean, or the
    change of the episode's running mean, signal_sum / steps counting this step's sample (steps >= 1)."""
    if self.reward.safety_form == "window":
      return jnp.mean(window)
    before = (signal_sum - window[0]) / jnp.maximum(steps - 1, 1)  # window[0]: this step's sample
    return signal_sum / steps - jnp.where(steps > 1, before, 0.0)

  def closeness(self, clearance: jax.Array) -> jax.Array:
    """(margin - clearance) / margin (m / m) where the clearance is below reward.clearance_margin, else 0."""
    margin = self.reward.clearance_margin
    return jnp.maximum(margin - clearance, 0.0) / margin

  def evaluate(self, dist, closest, d0, rpy, rate: jax.Array, k: jax.Array, collided: jax.Array,
               clearance: jax.Array | float = float("inf"), riding: jax.Array | bool = False):
    """Reward terms, new closest, terminated flag, flags dict for one step; rate: safety_rate(...);
    collided: whether the step's physics touched a wall or obstacle (mjx_tracks.sim.collisions);
    clearance: the footprint's distance (m) from the nearest wall (inf: not measured); riding:
    whether the step ended with a belt on a floor obstacle."""
    progress, closest = progress_step(dist, closest, d0, self.reward.progress_form)
    tipped = tipped_over(rpy)
    reached = goal_reached(dist)
    away = dist > self.episode.away_factor * d0
    terms = {
        "progress": self.reward.progress_scale * progress,
        "safety": -self.safety_scale() * k * rate,
        "tipover": -self.reward.tipover_penalty * tipped.astype(jnp.float32),
        "goal": self.reward.goal_bonus * reached.astype(jnp.float32),
        "collision": -self.reward.collision_penalty * collided.astype(jnp.float32),
        "clearance": -self.reward.clearance_penalty * self.closeness(clearance),
        "riding": -self.reward.riding_penalty * jnp.asarray(riding, jnp.float32),
    }
    ends = tipped | reached | away | (collided & self.episode.end_on_collision)
    return terms, progress, closest, ends, {"tipped": tipped, "reached": reached, "away": away, "collided": collided}

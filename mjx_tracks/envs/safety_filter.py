"""Safety filter: the robot's own laser scan vetoes a command that would bring it too near a wall.

A layer under the policy, as a real robot's collision-avoidance layer sits under its planner
(control.safety_filter; off unless enabled). At each control step, before the command reaches the
belts:

1. Sense: the filter's own horizontal ring of `rays` rays from the laser scanner
   (mjx_tracks.envs.scan, pitch 0: it passes over nav's floor obstacles and reads walls), with the
   scan's noise where the robustness suite perturbs it. Each hit within range is a point (x, y) in
   the chassis frame (m); a ray that hits nothing (or is lost: the filter then sees free space)
   gives none.
2. Predict: a command (v m/s, w rad/s) held for `horizon` s moves the chassis as a unicycle:
   yaw(t) = w t, x(t) = v sin(w t) / w, y(t) = v (1 - cos(w t)) / w (x = v t where w = 0), taken at
   `samples` times evenly spaced in (0, horizon].
3. Clearance: the least signed distance (m) of a point from the robot's footprint at those poses
   (negative inside it: minus the depth to its nearest edge). The footprint is the rectangle of half-sizes `half` round the chassis origin that holds every
   colliding geom at rest (mjx_tracks.sim.collisions.footprint_half: flippers in line, their longest
   reach; at any other flipper angle they reach less far).
4. Choose: of the candidates (a v, b w), a and b each in SCALES, the one nearest the command
   (|dv| / v_scale + |dw| / w_scale) whose clearance is at least `margin`, or, where the robot is
   already nearer than that (clearance standing still: now, negative where a hit lies inside the
   footprint), at least now: it never brings the robot nearer than margin, nor nearer than it is.
   Standing still always qualifies (for finite ranges); the command itself, where it qualifies, is
   kept; of equally near candidates, the one with the larger v.
Joint targets pass unchanged. The filter only scales v and w towards 0, never raising or reversing
them; scaling them unequally changes the path's curvature.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp

from mjx_tracks.envs.scan import ScanLayout

SCALES = (1.0, 0.75, 0.5, 0.25, 0.0)  # the fractions of v and of w the candidates keep
assert SCALES[0] == 1.0 and SCALES[-1] == 0.0  # choose(): the first candidate is the command, the last standing still
FAR = 1e3  # m, the clearance where the scan holds no point
ROUNDING = 1e-5  # m, float32 rounding allowed below the threshold (standing still meets it exactly)


def unicycle_poses(v: jax.Array, w: jax.Array, times: jax.Array) -> jax.Array:
  """(len(times), 3) chassis poses (x m, y m, yaw rad) after holding (v m/s, w rad/s) for each time (s),
  from the origin facing +x (module docstring, step 2)."""
  u = w * times  # rad
  small = jnp.abs(u) < 1e-4
  safe_u = jnp.where(small, 1.0, u)
  along = jnp.where(small, 1.0 - u ** 2 / 6.0, jnp.sin(safe_u) / safe_u)  # sin(u) / u
  across = jnp.where(small, u / 2.0, (1.0 - jnp.cos(safe_u)) / safe_u)  # (1 - cos u) / u
  return jnp.stack([v * times * along, v * times * across, u], axis=-1)


def footprint_distance(points: jax.Array, pose: jax.Array, half: jax.Array) -> jax.Array:
  """(N,) m: each point's (N, 2) signed distance from the rectangle of half-sizes half (2,) at pose
  (x, y, yaw): outside, the distance to it; inside, minus the distance to its nearest edge."""
  c, s = jnp.cos(pose[2]), jnp.sin(pose[2])
  rel = points - pose[:2]
  local = jnp.stack([c * rel[:, 0] + s * rel[:, 1], -s * rel[:, 0] + c * rel[:, 1]], axis=-1)
  excess = jnp.abs(local) - half  # (N, 2) m beyond each pair of edges (negative: inside them)
  return jnp.linalg.norm(jnp.maximum(excess, 0.0), axis=-1) + jnp.minimum(jnp.max(excess, axis=-1), 0.0)


@dataclasses.dataclass(frozen=True)
class SafetyFilter:
  """Static settings of the filter of one task (module docstring)."""

  scan: ScanLayout  # its ring: pitch 0 from the robot's laser scanner
  half: tuple[float, float]  # m, the footprint's half-sizes
  horizon: float  # s
  samples: int
  margin: float  # m
  v_scale: float  # m/s, |dv| of a full-range change (the robot's top speed)
  w_scale: float  # rad/s, |dw| of a full-range change (its top yaw rate)

  def points(self, ranges: jax.Array) -> tuple[jax.Array, jax.Array]:
    """((N, 2) m scan hits in the chassis frame, (N,) bool: a hit within range) of the ring's ranges (m)."""
    d = self.scan.directions()[:, :2]
    pts = jnp.asarray(self.scan.mount[:2], jnp.float32) + ranges[:, None] * jnp.asarray(d)
    return pts, ranges < self.scan.max_range

  def clearance(self, points: jax.Array, hit: jax.Array, v: jax.Array, w: jax.Array) -> jax.Array:
    """() m: the least signed distance of a hit from the footprint while (v, w) is held (steps 2-3)."""
    times = self.horizon * jnp.arange(1, self.samples + 1, dtype=jnp.float32) / self.samples
    poses = unicycle_poses(v, w, times)
    half = jnp.asarray(self.half, jnp.float32)
    dist = jax.vmap(lambda p: footprint_distance(points, p, half))(poses)  # (samples, N)
    return jnp.min(jnp.where(hit[None], dist, FAR))

  def choose(self, v: jax.Array, w: jax.Array, ranges: jax.Array) -> tuple[jax.Array, jax.Array, jax.Array]:
    """(v m/s, w rad/s, whether the command changed) for the command (v, w) and the ring's ranges (step 4)."""
    points, hit = self.points(ranges)
    a, b = (x.ravel() for x in jnp.meshgrid(jnp.asarray(SCALES), jnp.asarray(SCALES), indexing="ij"))
    cv, cw = a * v, b * w  # candidates; SCALES[0] == 1: the first is the command itself, the last standing still
    clear = jax.vmap(lambda x, y: self.clearance(points, hit, x, y))(cv, cw)
    now = clear[-1]  # standing still: the clearance where the robot is
    cost = jnp.abs(cv - v) / self.v_scale + jnp.abs(cw - w) / self.w_scale
    ok = clear >= jnp.minimum(self.margin, now) - ROUNDING
    pick = jnp.argmin(jnp.where(ok, cost, jnp.inf))  # the last candidate, standing still, is ok for finite ranges
    return cv[pick], cw[pick], cost[pick] > 0

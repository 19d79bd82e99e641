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
   `samples` times evenly spaced in (0, horizon]. With a `response` time tau > 0 s, the motion
   starts instead from the chassis's measured velocity (forward u0, sideways s0 m/s, yaw rate r0
   rad/s, in its own frame: what odometry and an IMU give a real robot) and approaches the command's
   as e^(-t / tau): body velocity (v + (u0 - v) e, s0 e, w + (r0 - w) e), e = e^(-t / tau),
   integrated in the plane (relaxed_poses). It sees a robot already turning or sliding (a floor
   obstacle pushing it, the lag of the belts) keep doing so for a while.
3. Clearance: the least signed distance (m) of a point from the robot's footprint at those poses
   (negative inside it: minus the depth to its nearest edge). The footprint is the rectangle of half-sizes `half` round the chassis origin that holds every
   colliding geom at rest (mjx_tracks.sim.collisions.footprint_half: flippers in line, their longest
   reach; at any other flipper angle they reach less far).
4. Choose: of the candidates (a v, b w), a and b each in SCALES, the one nearest the command
   (|dv| / v_scale + |dw| / w_scale) whose clearance is at least `margin`, or, where the robot is
   already nearer than that (clearance standing still: now, negative where a hit lies inside the
   footprint), at least now: it never brings the robot nearer than margin, nor nearer than it is.
   Standing still always qualifies (for finite ranges); the command itself, where it qualifies, is
   kept; of equally near candidates, the one with the larger v. (With a response time, "standing
   still" is stopping: its clearance is the robot's as it coasts to a halt.)
5. Back off (`reverse` > 0 m/s): where step 4 stops a robot the policy asked to move, the filter
   backs it up instead at -reverse m/s with the command's turn, its w scaled by the largest of SCALES
   that qualifies as in step 4 (w's sign unchanged: backing, the chassis turns the way the policy
   asked); where none does, it stands still. A held robot leaves the wall rather than wait there.
Joint targets pass unchanged. Without `reverse` the filter only scales v and w towards 0, never
raising or reversing them; scaling them unequally changes the path's curvature.
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


def relaxed_poses(v: jax.Array, w: jax.Array, measured: jax.Array, response: float, times: jax.Array,
                  fine: int = 8) -> jax.Array:
  """(len(times), 3) chassis poses (x m, y m, yaw rad) from the origin facing +x, with body velocity
  (v + (u0 - v) e, s0 e, w + (r0 - w) e), e = e^(-t / response) (module docstring, step 2), measured =
  (u0 m/s, s0 m/s, r0 rad/s). Yaw in closed form; the position by the midpoint rule, `fine` steps
  per interval between times (times evenly spaced from 0: times[k] = (k + 1) times[0])."""
  dt = times[0] / fine
  t = dt * (jnp.arange(len(times) * fine, dtype=jnp.float32) + 0.5)  # midpoints, s
  decay = lambda t: response * (1.0 - jnp.exp(-t / response))  # s, the integral of e over [0, t]
  yaw = lambda t: w * t + (measured[2] - w) * decay(t)
  e = jnp.exp(-t / response)
  u, s, th = v + (measured[0] - v) * e, measured[1] * e, yaw(t)
  x = jnp.cumsum((u * jnp.cos(th) - s * jnp.sin(th)) * dt)[fine - 1::fine]
  y = jnp.cumsum((u * jnp.sin(th) + s * jnp.cos(th)) * dt)[fine - 1::fine]
  return jnp.stack([x, y, yaw(times)], axis=-1)


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
  response: float = 0.0  # s, tau of step 2 (0: the command from the start, the unicycle)
  reverse: float = 0.0  # m/s, step 5's backing speed (0: never backs up)

  def points(self, ranges: jax.Array) -> tuple[jax.Array, jax.Array]:
    """((N, 2) m scan hits in the chassis frame, (N,) bool: a hit within range) of the ring's ranges (m)."""
    d = self.scan.directions()[:, :2]
    pts = jnp.asarray(self.scan.mount[:2], jnp.float32) + ranges[:, None] * jnp.asarray(d)
    return pts, ranges < self.scan.max_range

  def poses(self, v: jax.Array, w: jax.Array, measured: jax.Array | None, times: jax.Array) -> jax.Array:
    """(len(times), 3) predicted chassis poses (x m, y m, yaw rad) under (v, w) (step 2; times evenly
    spaced from 0 where there is a response time)."""
    if self.response == 0.0:
      return unicycle_poses(v, w, times)
    if measured is None:
      raise ValueError("a safety filter with a response time predicts from the measured velocity: pass measured")
    return relaxed_poses(v, w, measured, self.response, times)

  def clearance(self, points: jax.Array, hit: jax.Array, v: jax.Array, w: jax.Array,
                measured: jax.Array | None = None) -> jax.Array:
    """() m: the least signed distance of a hit from the footprint while (v, w) is held (steps 2-3);
    measured: the chassis's (u0 m/s, s0 m/s, r0 rad/s), read only with a response time."""
    times = self.horizon * jnp.arange(1, self.samples + 1, dtype=jnp.float32) / self.samples
    poses = self.poses(v, w, measured, times)
    half = jnp.asarray(self.half, jnp.float32)
    dist = jax.vmap(lambda p: footprint_distance(points, p, half))(poses)  # (samples, N)
    return jnp.min(jnp.where(hit[None], dist, FAR))

  def choose(self, v: jax.Array, w: jax.Array, ranges: jax.Array,
             measured: jax.Array | None = None) -> tuple[jax.Array, jax.Array, jax.Array]:
    """(v m/s, w rad/s, whether the command changed) for the command (v, w), the ring's ranges (m)
    and the chassis's measured (u0 m/s, s0 m/s, r0 rad/s) (steps 4-5; measured: read only with a
    response time)."""
    points, hit = self.points(ranges)
    clear_of = jax.vmap(lambda x, y: self.clearance(points, hit, x, y, measured))
    a, b = (x.ravel() for x in jnp.meshgrid(jnp.asarray(SCALES), jnp.asarray(SCALES), indexing="ij"))
    cv, cw = a * v, b * w  # candidates; SCALES[0] == 1: the first is the command itself, the last standing still
    clear = clear_of(cv, cw)
    now = clear[-1]  # standing still (stopping): the clearance it keeps
    cost = jnp.abs(cv - v) / self.v_scale + jnp.abs(cw - w) / self.w_scale
    floor = jnp.minimum(self.margin, now) - ROUNDING
    pick = jnp.argmin(jnp.where(clear >= floor, cost, jnp.inf))  # the last candidate, standing still, is ok for finite ranges
    v_out, w_out = cv[pick], cw[pick]
    if self.reverse > 0.0:  # step 5
      held = (v_out == 0.0) & (w_out == 0.0) & ((v != 0.0) | (w != 0.0))  # stopped, asked to move
      bv, bw = jnp.full(len(SCALES), -self.reverse, jnp.float32), jnp.asarray(SCALES) * w
      back_ok = clear_of(bv, bw) >= floor
      first = jnp.argmax(back_ok)  # the largest turn that qualifies (SCALES descending)
      backs = held & back_ok[first]
      v_out, w_out = jnp.where(backs, bv[first], v_out), jnp.where(backs, bw[first], w_out)
    return v_out, w_out, (v_out != v) | (w_out != w)

"""Safety filter (mjx_tracks.envs.safety_filter): its geometry against plain-Python references
(Euler-integrated unicycle, point-to-segment distances), its choice against a brute-force search
and hand-derived cases, and in the environment: full throttle at a wall stops short of it."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import mjx_tracks
from mjx_tracks.envs.config import ConfigError, load_config
from mjx_tracks.envs.safety_filter import SCALES, SafetyFilter, footprint_distance, relaxed_poses, unicycle_poses
from mjx_tracks.sim.pose import chassis_velocity
from mjx_tracks.envs.scan import ScanLayout

HALF = (0.505, 0.39)  # m, robot 1's footprint (test_collisions.py derives it)


def _euler_pose(v, w, t, n=20000):
  x = y = yaw = 0.0
  dt = t / n
  for _ in range(n):
    x += v * math.cos(yaw + 0.5 * w * dt) * dt
    y += v * math.sin(yaw + 0.5 * w * dt) * dt
    yaw += w * dt
  return x, y, yaw


@pytest.mark.parametrize("v,w", [(1.0, 0.0), (0.6, 1.0), (0.3, -0.7), (0.0, 1.0), (0.8, 1e-6)])
def test_unicycle_poses_match_integrated_motion(v, w):
  times = np.array([0.1, 0.25, 0.5], np.float32)
  got = np.asarray(unicycle_poses(jnp.float32(v), jnp.float32(w), jnp.asarray(times)))
  for t, pose in zip(times, got):
    assert pose == pytest.approx(_euler_pose(v, w, float(t)), abs=2e-5)


def _euler_relaxed_pose(v, w, measured, tau, t, n=20000):
  """Plain reference of relaxed_poses: body velocity (v + (u0 - v) e, s0 e, w + (r0 - w) e),
  e = exp(-t / tau), integrated by small Euler steps in the plane."""
  u0, s0, r0 = measured
  x = y = yaw = 0.0
  dt = t / n
  for i in range(n):
    e = math.exp(-(i + 0.5) * dt / tau)
    u, s, r = v + (u0 - v) * e, s0 * e, w + (r0 - w) * e
    mid = yaw + 0.5 * r * dt
    x += (u * math.cos(mid) - s * math.sin(mid)) * dt
    y += (u * math.sin(mid) + s * math.cos(mid)) * dt
    yaw += r * dt
  return x, y, yaw


@pytest.mark.parametrize("v,w,measured,tau", [(0.8, 0.5, (0.2, -0.3, -1.5), 0.25), (0.0, 0.0, (0.0, 0.4, 0.0), 0.1),
                                              (1.0, -0.7, (1.0, 0.0, -0.7), 0.5), (0.5, 1.0, (0.9, 0.1, 0.0), 1.0)])
def test_relaxed_poses_match_integrated_motion(v, w, measured, tau):
  times = np.array([0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.45, 0.5], np.float32)
  got = np.asarray(relaxed_poses(jnp.float32(v), jnp.float32(w), jnp.asarray(measured, jnp.float32), tau,
                                 jnp.asarray(times)))
  for t, pose in zip(times, got):
    assert pose == pytest.approx(_euler_relaxed_pose(v, w, measured, tau, float(t)), abs=2e-4)
  if measured == (v, 0.0, w):  # already moving as commanded: the unicycle
    assert got == pytest.approx(np.asarray(unicycle_poses(jnp.float32(v), jnp.float32(w), jnp.asarray(times))), abs=2e-4)
  if v == w == 0.0:  # a slide dying away: y(t) = s0 tau (1 - e^(-t / tau)), by hand
    assert got[:, 1] == pytest.approx(measured[1] * tau * (1 - np.exp(-times / tau)), abs=1e-5)


def test_chassis_velocity_is_read_in_the_chassis_frame():
  """A chassis yawed 90 degrees left (its x axis along world +y) moving along world +y drives forward;
  along world +x it slides to its right (-y)."""
  rot = jnp.asarray([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # columns: the chassis's axes in world
  assert np.asarray(chassis_velocity(rot, jnp.asarray([0.0, 0.7, 0.0, 0, 0, 0]))) == pytest.approx([0.7, 0.0, 0.0])
  assert np.asarray(chassis_velocity(rot, jnp.asarray([0.3, 0.0, 0.0, 0, 0, 0]))) == pytest.approx([0.0, -0.3, 0.0])


def _segment_distance(p, a, b):
  ab, ap = b - a, p - a
  s = np.clip(ap @ ab / (ab @ ab), 0.0, 1.0)
  return float(np.linalg.norm(ap - s * ab))


def _rect_distance(p, pose, half):
  """Plain reference: the least distance to the rectangle's four edges, negative inside."""
  c, s = math.cos(pose[2]), math.sin(pose[2])
  corners = [np.array([pose[0] + c * x - s * y, pose[1] + s * x + c * y])
             for x, y in ((half[0], half[1]), (-half[0], half[1]), (-half[0], -half[1]), (half[0], -half[1]))]
  local = np.array([c * (p[0] - pose[0]) + s * (p[1] - pose[1]), -s * (p[0] - pose[0]) + c * (p[1] - pose[1])])
  edges = min(_segment_distance(p, corners[i], corners[(i + 1) % 4]) for i in range(4))
  return -edges if abs(local[0]) <= half[0] and abs(local[1]) <= half[1] else edges


def test_footprint_distance_matches_edge_distances():
  rng = np.random.default_rng(0)
  points = rng.uniform(-1.5, 1.5, (200, 2))
  for pose in ([0.0, 0.0, 0.0], [0.3, -0.2, 0.7], [-0.5, 0.4, -2.5]):
    got = np.asarray(footprint_distance(jnp.asarray(points, jnp.float32), jnp.asarray(pose, jnp.float32), jnp.asarray(HALF)))
    want = [_rect_distance(p, pose, HALF) for p in points]
    assert got == pytest.approx(want, abs=1e-5)
  assert (np.asarray(got) < 0).any() and (np.asarray(got) > 0).any()  # both sides of the edges were sampled


def _filter(rays=8, horizon=0.5, samples=10, margin=0.05, response=0.0, reverse=0.0):
  return SafetyFilter(ScanLayout(rays, 5.0, (0.0, 0.0, 0.2), (0.0,)), HALF, horizon, samples, margin, 1.0, 1.0,
                      response, reverse)


def _ranges(f, hits: dict[int, float]):
  """The ring's ranges with ray k hitting at hits[k] m, the others reading nothing (max range)."""
  r = np.full(f.scan.n_rays, f.scan.max_range, np.float32)
  for k, d in hits.items():
    r[k] = d
  return jnp.asarray(r)


def test_clearance_of_a_straight_drive_is_the_hand_derived_gap():
  f = _filter()
  points, hit = f.points(_ranges(f, {0: 2.0}))  # a point 2 m straight ahead
  for v in (0.0, 0.5, 1.0):
    assert float(f.clearance(points, hit, jnp.float32(v), jnp.float32(0.0))) == pytest.approx(2.0 - 0.505 - 0.5 * v, abs=1e-5)
  none = jnp.zeros(f.scan.n_rays, bool)
  assert float(f.clearance(points, none, jnp.float32(1.0), jnp.float32(0.0))) >= 100.0  # no hit: nothing near


def _plain_clearance(f, points, v, w):
  """The least signed distance of the points from the footprint along (v, w) held, in plain Python
  (closed-form unicycle poses, _rect_distance)."""
  out = math.inf
  for j in range(1, f.samples + 1):
    t = f.horizon * j / f.samples
    u = w * t
    x, y = (v * t, 0.0) if abs(u) < 1e-9 else (v * math.sin(u) / w, v * (1 - math.cos(u)) / w)
    out = min([out, *(_rect_distance(p, (x, y, u), HALF) for p in points)])
  return out


def _brute_force_choice(f, v, w, points):
  """The rule of the module docstring, step 4, by enumeration in plain Python."""
  cands = [(a * v, b * w) for a in SCALES for b in SCALES]
  now = _plain_clearance(f, points, 0.0, 0.0)
  ok = [(abs(x - v) + abs(y - w), i) for i, (x, y) in enumerate(cands)
        if _plain_clearance(f, points, x, y) >= min(f.margin, now) - 1e-5]
  return cands[min(ok)[1]]


def test_choice_slows_just_enough_and_matches_brute_force():
  f = _filter()
  # a wall point 1.05 m ahead: clearance 0.545 - 0.5 a v >= 0.05 keeps a <= 0.99 at v = 1: 0.75 is the largest safe scale
  points, hit = f.points(_ranges(f, {0: 1.05}))
  v, w, changed = f.choose(jnp.float32(1.0), jnp.float32(0.0), _ranges(f, {0: 1.05}))
  assert (float(v), float(w), bool(changed)) == (0.75, 0.0, True)
  v, w, changed = f.choose(jnp.float32(0.5), jnp.float32(0.0), _ranges(f, {0: 1.05}))
  assert (float(v), bool(changed)) == (0.5, False)  # already safe: unchanged
  rng = np.random.default_rng(1)
  changed = inside = 0
  for _ in range(16):  # random points round the robot, some inside the footprint; commands turning either way
    ranges = _ranges(f, {int(k): float(rng.uniform(0.35, 1.1)) for k in rng.choice(8, 3, replace=False)})
    cmd = (float(rng.uniform(0, 1)), float(rng.uniform(-1, 1)))
    points, hit = f.points(ranges)
    pts = [np.asarray(p, np.float64) for p, h in zip(np.asarray(points), np.asarray(hit)) if h]
    got = f.choose(jnp.float32(cmd[0]), jnp.float32(cmd[1]), ranges)
    assert (float(got[0]), float(got[1])) == pytest.approx(_brute_force_choice(f, *cmd, pts), abs=1e-5)
    changed += bool(got[2])
    inside += _plain_clearance(f, pts, 0.0, 0.0) < 0
  assert changed >= 6 and inside >= 2  # the draws exercise the choice, also from inside the footprint


def test_a_turn_that_sweeps_a_corner_into_a_wall_is_slowed():
  """Turning in place by theta, a point 0.605 m ahead on the centre line lies 0.605 cos(theta) along
  the chassis: its clearance 0.605 cos(theta) - 0.505 stays >= the 0.05 m margin while theta <=
  acos(0.555 / 0.605) = 0.409 rad. In the 0.5 s horizon, 1 rad/s turns 0.5 rad (unsafe), 0.75 rad/s
  0.375 rad (safe): the filter keeps three quarters of the turn."""
  f = _filter(rays=8)
  v, w, changed = f.choose(jnp.float32(0.0), jnp.float32(1.0), _ranges(f, {0: 0.605}))
  assert (float(v), float(w), bool(changed)) == (0.0, 0.75, True)
  v, w, changed = f.choose(jnp.float32(0.0), jnp.float32(-1.0), _ranges(f, {0: 0.605}))
  assert (float(w), bool(changed)) == (-0.75, True)  # either way round


def test_a_hit_inside_the_footprint_refuses_going_deeper():
  """A hit 0.45 m ahead lies 0.055 m inside the front edge (0.505 m): driving on takes it deeper, and
  so does turning (its depth from the front edge, 0.505 - 0.45 cos(theta), grows): only standing still
  keeps it no deeper; backing away (a reverse speed) is kept."""
  f = _filter()
  assert tuple(map(float, f.choose(jnp.float32(1.0), jnp.float32(0.5), _ranges(f, {0: 0.45})))) == (0.0, 0.0, 1.0)
  assert tuple(map(float, f.choose(jnp.float32(-0.5), jnp.float32(0.0), _ranges(f, {0: 0.45})))) == (-0.5, 0.0, 0.0)


def test_backing_up_is_checked_against_what_lies_behind():
  """With a reverse speed (control.v_range below 0), a point 0.8 m behind (ray 4 of 8): backing at
  0.5 m/s for 0.5 s leaves 0.8 - 0.505 - 0.25 = 0.045 m (< 0.05: unsafe), at 0.375 m/s 0.1075 m: the
  filter keeps three quarters of the speed; a point 0.8 m ahead lets the same reverse command through."""
  f = _filter()
  v, w, changed = f.choose(jnp.float32(-0.5), jnp.float32(0.0), _ranges(f, {4: 0.8}))
  assert (float(v), bool(changed)) == (-0.375, True)
  v, w, changed = f.choose(jnp.float32(-0.5), jnp.float32(0.0), _ranges(f, {0: 0.8}))
  assert (float(v), bool(changed)) == (-0.5, False)


def test_alongside_a_wall_inside_the_margin_it_keeps_a_parallel_course_and_stops_the_swing():
  """A wall 0.03 m beside the footprint's left side (y = 0.42 m; margin 0.05): driving straight keeps
  the 0.03 m (kept: the filter never traps the robot where it is), while turning either way swings a
  corner towards the wall (left: the front one; right: the rear one, the centre's 0.12 m step away
  in 0.5 s at 1 m/s being less than the corner's 0.19 m swing): the turn is dropped, the speed kept."""
  f = _filter(rays=180)
  angle = 2 * np.pi * np.arange(180) / 180
  ranges = jnp.asarray(np.where(np.sin(angle) > 0.1, 0.42 / np.maximum(np.sin(angle), 1e-9), 5.0).clip(max=5.0), jnp.float32)
  for w in (0.0, 1.0, -1.0):
    got = tuple(map(float, f.choose(jnp.float32(1.0), jnp.float32(w), ranges)))
    assert got == (1.0, 0.0, float(w != 0.0)), w


def test_a_robot_moving_faster_than_its_command_is_slowed_sooner():
  """A wall point 1.05 m ahead (clearance 0.545 m at rest, margin 0.05), command 0.5 m/s straight.
  As a unicycle the robot travels 0.25 m in the 0.5 s: kept. Measured at 2 m/s forward (pushed, or
  the belts still slowing) with tau = 0.25 s, a v travels 0.5 a v + (2 - a v) D, D = tau (1 - e^-2) =
  0.2162 s: clearance 0.1126 - 0.2838 a v >= 0.05 keeps a v <= 0.2206: of 0.5 x SCALES, 0.125 m/s."""
  ranges = _ranges(_filter(), {0: 1.05})
  measured = jnp.asarray([2.0, 0.0, 0.0])
  assert tuple(map(float, _filter().choose(jnp.float32(0.5), jnp.float32(0.0), ranges, measured))) == (0.5, 0.0, 0.0)
  v, w, changed = _filter(response=0.25).choose(jnp.float32(0.5), jnp.float32(0.0), ranges, measured)
  assert (float(v), float(w), bool(changed)) == (0.125, 0.0, True)
  with pytest.raises(ValueError, match="measured"):
    _filter(response=0.25).choose(jnp.float32(0.5), jnp.float32(0.0), ranges)


def test_a_held_robot_backs_away_with_the_commanded_turn():
  """A hit 0.45 m ahead, inside the front edge: the filter stops the command (test above). With a
  reverse speed of 0.3 m/s it backs up turning as the policy asked (backing 0.15 m while turning
  0.25 rad takes the hit further from the front edge throughout); a second hit 0.52 m behind (0.015 m
  outside the rear edge) refuses backing at any turn: it stands. A robot asked to stand is not moved."""
  f = _filter(reverse=0.3)
  assert tuple(map(float, f.choose(jnp.float32(1.0), jnp.float32(0.5), _ranges(f, {0: 0.45})))) == pytest.approx((-0.3, 0.5, 1.0))
  assert tuple(map(float, f.choose(jnp.float32(1.0), jnp.float32(0.5), _ranges(f, {0: 0.45, 4: 0.52})))) == (0.0, 0.0, 1.0)
  assert tuple(map(float, f.choose(jnp.float32(0.0), jnp.float32(0.0), _ranges(f, {0: 0.45})))) == (0.0, 0.0, 0.0)
  # straight ahead (w = 0) and turning in place (v = 0): stopped, it backs up straight (w x any scale is 0)
  # or with the turn
  assert tuple(map(float, f.choose(jnp.float32(1.0), jnp.float32(0.0), _ranges(f, {0: 0.45})))) == pytest.approx((-0.3, 0.0, 1.0))
  assert tuple(map(float, f.choose(jnp.float32(0.0), jnp.float32(0.5), _ranges(f, {0: 0.45})))) == pytest.approx((-0.3, 0.5, 1.0))
  assert tuple(map(float, f.choose(jnp.float32(0.5), jnp.float32(0.0), _ranges(f, {0: 1.05})))) == (0.5, 0.0, 0.0)  # not held


def test_config_refuses_the_filter_where_nothing_is_a_wall():
  with pytest.raises(ConfigError, match="safety_filter"):
    load_config("asc-inc-cog", ["control.safety_filter.enabled=true"])
  with pytest.raises(ConfigError, match="margin"):
    load_config("nav", ["control.safety_filter.margin=-0.1"])


def test_full_throttle_at_a_wall_stops_short_of_it():
  """Full throttle for 16 control steps (4 s) from x = 3 m, heading +x at a wall obstacle whose face
  is at x = 6 m: unfiltered, the front (x + 0.505 m) would reach the face within 2.5 s at up to
  1 m/s (the collision watch flags the touch: test_collisions.py). With the filter the robot drives
  up to the wall, never touches it and stops as near as the margin lets it."""
  env = mjx_tracks.load("nav", ["control.safety_filter.enabled=true"])
  state0 = jax.jit(env.reset)(jax.random.PRNGKey(0))  # one program, not ~450 eager ones

  def drive(x):
    es = state0.pipeline_state
    pos = es.scene.box_pos.at[0].set(jnp.array([6.5, 0.0, 0.5])).at[1].set(jnp.array([-20.0, 0.0, -5.0]))
    size = es.scene.box_size.at[0].set(jnp.array([0.5, 0.6, 0.5]))
    scene = es.scene.replace(box_pos=pos, box_size=size, box_yaw=es.scene.box_yaw.at[0].set(0.0))
    data = env._sense(env._model(scene, None), env.sim.init_data(jnp.array([x, 0.0, 0.0]), jnp.float32(0.0)))
    s = state0.replace(pipeline_state=es.replace(scene=scene, data=data))
    full = jnp.array([1.0, 0.0, 0.0, 0.0])  # 4dof: v at its top, no turn, flippers held

    def body(s, _):
      n = env.step(s, full)
      return n, (n.pipeline_state.collided, n.metrics["command_filtered"])
    s, (collided, filtered) = jax.lax.scan(body, s, None, length=16)
    return collided.any(), s.pipeline_state.data.qpos[0], filtered.sum()

  collided, x, filtered = map(float, jax.jit(drive)(jnp.float32(3.0)))
  gap = 6.0 - (x + 0.505)  # m, the footprint's front to the wall
  assert not collided and filtered > 0
  # it stops once even a quarter of the speed, held 0.5 s (0.125 m), would leave less than the 0.1 m margin:
  # at a gap in [0.1, 0.225] m, give or take a little prediction error and coasting
  assert 0.08 <= gap <= 0.26

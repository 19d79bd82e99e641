"""Sim-to-real randomization (mjx_tracks.envs.randomization): each draw against its distribution,
each quantity against its effect: hand-derived centre of mass, a slide whose length goes as 1 / mu,
belt gains, late commands, a jittered period, sensor noise statistics, a tilted camera against
mujoco.mj_ray. One program (TrackedRobotEnv every_path) serves every physics case here."""

import dataclasses

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
import pytest

from mjx_tracks.envs import randomization as rnd
from mjx_tracks.envs.config import load_config

N = 4000  # draws for the distribution tests


def _draws(c, eps=1.0, n=N):
  keys = jax.random.split(jax.random.PRNGKey(0), n)
  return jax.vmap(lambda k: rnd.draw(c, k, jnp.float32(eps), 6, 0.1, 0.25))(keys)


def test_draws_follow_their_distributions():
  """Each [min, max] key ~ U(min, max) (mean, variance (b - a)^2 / 12), each half-width ~ U(-a, a),
  the delay uniform over the integers min..max, noise levels as configured."""
  c = dataclasses.replace(load_config("asc-inc-cog-robust").randomization, action_delay=(0, 4))
  p = _draws(c)
  for x, (lo, hi) in [(p.friction[:, 0], c.friction_along), (p.friction[:, 1], c.friction_across),
                      (p.mass, c.mass), (p.payload, c.payload), (p.belt_gain[:, 0], c.belt_gain),
                      (p.belt_gain[:, 1], c.belt_gain), (p.servo_gain, c.servo_gain),
                      (p.camera_pitch, c.camera_pitch), (p.com_offset[:, 0], (-c.com_offset[0], c.com_offset[0])),
                      (p.joint_bias[:, 3], (-c.joint_bias, c.joint_bias)), (p.imu_bias[:, 1], (-c.imu_bias[0], c.imu_bias[0]))]:
    x = np.asarray(x)
    assert lo <= x.min() and x.max() <= hi
    sd_mean = (hi - lo) / np.sqrt(12 * N)
    assert abs(x.mean() - (lo + hi) / 2) < 5 * sd_mean
    assert x.var() == pytest.approx((hi - lo) ** 2 / 12, rel=0.1)
  counts = np.bincount(np.asarray(p.delay), minlength=5)
  assert len(counts) == 5 and np.all(np.abs(counts - N / 5) < 5 * np.sqrt(N / 5))
  assert np.corrcoef(np.asarray(p.belt_gain).T)[0, 1] < 0.1  # the two sides drawn apart
  np.testing.assert_allclose(np.asarray(p.imu_noise[0]), c.imu_noise)
  assert float(p.push_probability[0]) == pytest.approx(0.25 / c.push_interval)


def test_off_is_the_nominal_robot_and_grow_widens_with_eps():
  c = load_config("asc-inc-cog-robust").randomization
  off = _draws(dataclasses.replace(c, enabled=False), n=50)
  for name, value in [("friction", 1.0), ("mass", 1.0), ("payload", 0.0), ("belt_gain", 1.0), ("delay", 0),
                      ("imu_noise", 0.0), ("joint_bias", 0.0), ("camera_pitch", 0.0), ("push_probability", 0.0)]:
    np.testing.assert_array_equal(np.asarray(getattr(off, name)), value)
  grown = dataclasses.replace(c, grow=True)
  assert float(jnp.max(_draws(grown, eps=0.0, n=50).mass)) == 1.0
  half = _draws(grown, eps=0.5)
  lo, hi = c.mass
  assert 1 + 0.5 * (lo - 1) <= float(half.mass.min()) and float(half.mass.max()) <= 1 + 0.5 * (hi - 1)
  assert float(half.mass.max()) > 1 + 0.45 * (hi - 1)


def test_mass_payload_and_centre_of_mass_move_the_robots_centre_of_mass(jaguar_stairs):
  """The whole robot's centre of mass (MJX subtree_com of the chassis) against the hand-weighted
  mean: the chassis' mass scaled, the payload added at its centre, that centre moved."""
  from mujoco import mjx
  sim = jaguar_stairs
  b = sim.layout.chassis_body
  p = _draws(load_config("asc-inc-cog-robust").randomization, n=1)
  p = jax.tree_util.tree_map(lambda x: x[0], p).replace(
      mass=jnp.float32(1.2), payload=jnp.float32(2.0), com_offset=jnp.array([0.05, -0.03, 0.02]))
  d = sim.init_data(jnp.zeros(3), jnp.float32(0.0), jnp.zeros(sim.layout.n_joints))
  m = rnd.with_dynamics(sim.model, p, b, sim.layout.joint_qvel)
  com = lambda model: np.asarray(jax.jit(lambda mm: mjx.com_pos(mm, mjx.kinematics(mm, d)))(model).subtree_com[b])
  c0, c1 = com(sim.model), com(m)
  mj = sim.mj_model
  masses = np.asarray(mj.body_mass)
  total0 = masses[1:].sum()
  cd = mujoco.MjData(mj)
  cd.qpos[:] = np.asarray(d.qpos)
  mujoco.mj_forward(mj, cd)
  chassis0 = cd.xipos[b].copy()
  moved = chassis0 + cd.xmat[b].reshape(3, 3) @ np.array([0.05, -0.03, 0.02])
  new_chassis = masses[b] * 1.2 + 2.0
  expected = (c0 * total0 - masses[b] * chassis0 + new_chassis * moved) / (total0 - masses[b] + new_chassis)
  np.testing.assert_allclose(c1, expected, atol=1e-5)
  assert float(m.actuator_gainprm[0, 0]) == pytest.approx(float(sim.model.actuator_gainprm[0, 0]) * float(p.servo_gain))


@pytest.fixture(scope="module")
def robust_core():
  """(core, reset(keys, perturbations), step): the stair task with every randomization path compiled,
  observing its belts' encoders last (part belt_speed)."""
  from mjx_tracks.envs.task_env import TrackedRobotEnv
  parts = [*load_config("asc-inc-cog").observation.parts, "belt_speed"]
  core = TrackedRobotEnv(load_config("asc-inc-cog", [f"observation.parts=[{', '.join(parts)}]"]), every_path=True)
  reset = jax.jit(jax.vmap(core.reset_at, in_axes=(0, None, None, 0)))
  step = jax.jit(jax.vmap(core.step))
  return core, (lambda keys, p: reset(keys, jnp.float32(0.0), jnp.float32(1.0), p)), step


def _batch(core, **changes_per_env):
  """A batch of nominal perturbations, env i's fields replaced by changes_per_env[field][i]."""
  n = len(next(iter(changes_per_env.values())))
  p = core.draw_perturbation(jax.random.PRNGKey(0), jnp.float32(0.0))
  p = p.replace(push_probability=jnp.float32(0.0))
  batch = jax.tree_util.tree_map(lambda x: jnp.stack([x] * n), p)
  return batch.replace(**{k: jnp.stack([jnp.asarray(v, getattr(p, k).dtype) for v in vals])
                          for k, vals in changes_per_env.items()})


def test_gains_delay_and_jitter_act_on_the_physics(robust_core):
  """Full speed ahead on the flat approach: belt gains 0.8 (left) and 0.6 (right) read 0.8 and 0.6 m/s
  on the encoders (0 at rest) and belt gains 0.8 cover 0.8 of the distance in two control steps; a
  command one period late leaves the robot where it started after the first step, its encoders at
  rest; a jittered period lasts 25 + U{-3..3} substeps (four steps)."""
  core, reset, step = robust_core
  p = _batch(core, belt_gain=[[1, 1], [0.8, 0.8], [1, 1], [0.8, 0.6]], delay=[0, 0, 25, 0], period_jitter=[0, 0, 0, 3])
  keys = jnp.stack([jax.random.PRNGKey(3)] * 4)
  s = reset(keys, p)
  np.testing.assert_array_equal(np.asarray(s.obs[:, -2:]), 0.0)  # the belts at rest
  x0 = np.asarray(s.pipeline_state.data.qpos[:, 0])
  act = jnp.ones((4, core.action_size)).at[:, 1:].set(0.0)
  s = step(s, act)
  # v = 1 m/s on both sides (w = 0), times each side's gain, on the encoders; the late one still runs
  # the command before it (at rest) at the period's end
  np.testing.assert_allclose(np.asarray(s.obs[:, -2:]), [[1, 1], [0.8, 0.8], [0, 0], [0.8, 0.6]], atol=1e-6)
  moved1 = np.asarray(s.pipeline_state.data.qpos[:, 0]) - x0
  times = [np.asarray(s.pipeline_state.data.time)]
  for i in range(3):
    s = step(s, act)
    times.append(np.asarray(s.pipeline_state.data.time))
    if i == 0:  # 0.5 s: before the first step of the staircase
      moved = np.asarray(s.pipeline_state.data.qpos[:, 0]) - x0
  assert moved[0] > 0.4
  assert moved[1] / moved[0] == pytest.approx(0.8, abs=0.05)
  assert abs(moved1[2]) < 0.01 < moved1[0]
  assert times[-1][0] == pytest.approx(1.0, abs=1e-4)
  steps = np.round(np.diff(np.concatenate([[0.0], np.stack(times)[:, 3]])) / 0.01)
  assert np.all((22 <= steps) & (steps <= 28)) and np.any(steps != 25)


def test_the_belt_speed_part_averages_each_sides_belts():
  """BELT_SIDE order: left track, right track, then the flippers' belts alternating left, right."""
  from mjx_tracks.envs.observations import PARTS, Sensors
  from mjx_tracks.robots import get_robot
  spec = Sensors.spec(6, 0, 0, 0)
  s = Sensors(*[jnp.zeros(x.shape) for x in jax.tree_util.tree_leaves(spec)[:-1]],
              belts=jnp.array([1.0, -0.5, 0.4, 0.1, 0.7, 0.3]))
  np.testing.assert_allclose(PARTS["belt_speed"].extract(s, get_robot(1)), [0.7, -0.1 / 3], rtol=1e-6)


def test_a_push_slides_twice_as_far_on_half_the_friction(robust_core):
  """A 1 m/s push with the belts stopped: the slide v^2 / (2 mu g) doubles when every friction
  coefficient halves (same push direction: same key)."""
  core, reset, step = robust_core
  # a batch of 4 (the pair twice), the batch the test above compiles its programs for
  p = _batch(core, friction=[[1, 1], [0.5, 0.5]] * 2, push_velocity=[1.0] * 4, push_probability=[1.0] * 4)
  s = reset(jnp.stack([jax.random.PRNGKey(4)] * 4), p)
  xy0 = np.asarray(s.pipeline_state.data.qpos[:, :2])
  # v = 0, joints held; zeros, not jnp.full(.., 0.0): a weakly typed action is another program
  stop = jnp.zeros((4, core.action_size)).at[:, 0].set(-1.0)
  s = step(s, stop)
  es = s.pipeline_state
  pert = es.robust.perturbation  # no more pushes
  s = s.replace(pipeline_state=es.replace(robust=es.robust.replace(
      perturbation=pert.replace(push_probability=pert.push_probability.at[:].set(0.0)))))
  for _ in range(3):
    s = step(s, stop)
  slide = np.linalg.norm(np.asarray(s.pipeline_state.data.qpos[:, :2]) - xy0, axis=1)
  np.testing.assert_array_equal(slide[2:], slide[:2])  # the same pair: the same slides
  assert slide[0] > 0.03
  assert slide[1] / slide[0] == pytest.approx(2.0, rel=0.3)


def test_sensor_noise_and_bias_have_their_statistics():
  """noisy_imu_and_joints: Gaussian noise of the configured std; biases fixed per episode."""
  c = dataclasses.replace(load_config("asc-inc-cog-robust").randomization, imu_noise=(0.1, 0.2, 0.3),
                          joint_noise=0.05)
  p = jax.tree_util.tree_map(lambda x: x[0], _draws(c, n=1))
  z3, z6 = jnp.zeros(3), jnp.zeros(6)
  out = jax.vmap(lambda k: rnd.noisy_imu_and_joints(p, z3, z3, z3, z6, k))(jax.random.split(jax.random.PRNGKey(1), N))
  for x, bias, sd in [(out[0][:, 1], p.imu_bias[1], 0.1), (out[1][:, 0], p.imu_bias[2], 0.2),
                      (out[2][:, 2], 0.0, 0.3), (out[3][:, 4], p.joint_bias[4], 0.05)]:
    x = np.asarray(x)
    assert abs(x.mean() - float(bias)) < 5 * sd / np.sqrt(N)
    assert x.std() == pytest.approx(sd, rel=0.06)
  assert float(out[0][0, 2]) == 0.0  # yaw is not the IMU's


def test_a_tilted_camera_sees_what_mj_ray_sees_from_the_tilted_mount(jaguar_stairs):
  """cast with camera pitch p against mujoco.mj_ray from the camera site turned by p about its x
  axis in the C model (mju_mulQuat: MuJoCo's own composition); p > 0 looks down (nearer floor)."""
  from mjx_tracks.envs.beams import BeamLayout, cast
  from mujoco import mjx
  sim = jaguar_stairs
  layout = BeamLayout.create(1.2, (640, 480), 20, 0, 10, (1, 1), (0.2, 1.5), 8.0)
  d = sim.init_data(jnp.array([-1.0, 0.0, 0.0]), jnp.float32(0.0), jnp.zeros(sim.layout.n_joints))
  d = jax.jit(mjx.kinematics)(sim.model, d)
  cam = sim.layout.camera_site
  tilted = jax.jit(lambda m, d, pitch: cast(layout, m, d, cam, pitch))  # one program, not ~100 eager ones a cast
  for pitch in (0.0873, -0.0873):
    depth = np.asarray(tilted(sim.model, d, jnp.float32(pitch)))
    mj = sim.c_model_with_boxes(np.asarray(sim.model.geom_pos)[sim.layout.scene_boxes],
                                np.asarray(sim.model.geom_size)[sim.layout.scene_boxes])
    turn = np.zeros(4)
    mujoco.mju_axisAngle2Quat(turn, np.array([1.0, 0.0, 0.0]), -pitch)
    quat = np.zeros(4)
    mujoco.mju_mulQuat(quat, mj.site_quat[cam].copy(), turn)
    mj.site_quat[cam] = quat
    data = mujoco.MjData(mj)
    data.qpos[:] = np.asarray(d.qpos)
    mujoco.mj_forward(mj, data)
    pnt, vecs = layout.world_rays(data.site_xpos[cam], data.site_xmat[cam].reshape(3, 3))
    oracle = np.array([mujoco.mj_ray(mj, data, np.asarray(pnt, np.float64), np.asarray(v, np.float64),
                                     np.array([1, 0, 0, 0, 0, 0], np.uint8), 1, -1, np.zeros(1, np.int32))
                       for v in np.asarray(vecs)])
    np.testing.assert_allclose(depth, oracle, atol=2e-3)
    assert (oracle >= 0).sum() > 5
  level = np.asarray(cast(layout, sim.model, d, cam))
  down = np.asarray(tilted(sim.model, d, jnp.float32(0.0873)))
  floor = (level > 0) & (down > 0)
  assert np.median(down[floor] - level[floor]) < 0  # looking down: the floor comes nearer


def test_depth_range_noise_is_relative_and_misses_stay_misses():
  """with_range_noise: a 2 m hit reads 2 x (1 + N(0, 0.05)) (std 0.1 m); a miss (-1) stays -1."""
  from mjx_tracks.envs.beams import with_range_noise
  depth = jnp.concatenate([jnp.full(N, 2.0), jnp.full(10, -1.0)])
  got = np.asarray(with_range_noise(depth, 0.05, jax.random.PRNGKey(2)))
  assert abs(got[:N].mean() - 2.0) < 5 * 0.1 / np.sqrt(N)
  assert got[:N].std() == pytest.approx(0.1, rel=0.06)
  np.testing.assert_array_equal(got[N:], -1.0)


def test_pushes_come_at_their_rate_with_their_speed_in_any_direction():
  """push: pushed with probability period / push_interval; a push adds push_velocity (m/s) to the
  chassis' horizontal velocity, its direction ~ U(0, 2 pi) (mean of cos and sin 0)."""
  c = dataclasses.replace(load_config("asc-inc-cog-robust").randomization, push_velocity=0.7, push_interval=1.0)
  p = jax.tree_util.tree_map(lambda x: x[0], _draws(c, n=1))  # probability 0.25 / 1.0
  qvel, pushed = jax.vmap(lambda k: rnd.push(jnp.zeros(12), p, k))(jax.random.split(jax.random.PRNGKey(5), N))
  pushed, kick = np.asarray(pushed), np.asarray(qvel[:, :2])
  assert abs(pushed.mean() - 0.25) < 5 * np.sqrt(0.25 * 0.75 / N)
  np.testing.assert_allclose(np.linalg.norm(kick[pushed], axis=1), 0.7, rtol=1e-5)
  assert np.all(kick[~pushed] == 0) and np.all(np.asarray(qvel[:, 2:]) == 0)
  assert np.all(np.abs(kick[pushed].mean(axis=0)) < 5 * 0.7 / np.sqrt(2 * pushed.sum()))


def test_a_task_file_extends_another_and_robustness_cases_are_checked_on_load(tmp_path, monkeypatch):
  """-robust tasks are their paper task plus randomization; a bad case (a key that does not exist,
  a value out of range, enabled) fails on load naming it; a case runs with grow off at any eps."""
  from mjx_tracks.envs.config import ConfigError
  from train.evaluation import scene_config
  base, robust = load_config("asc-inc-cog").to_dict(), load_config("asc-inc-cog-robust").to_dict()
  differ = {k for k in base if base[k] != robust[k]}
  assert differ == {"task", "randomization", "observation"} and robust["task"] == "asc-inc-cog-robust"
  for bad in ("randomization.frixion=[0.5, 0.5]", "randomization.mass=[0.1, 0.1]", "randomization.enabled=false"):
    with pytest.raises(ConfigError, match="robustness"):
      load_config("asc-inc-cog", [f'evaluation.robustness=[{{name: x, set: ["{bad}"]}}]'])
  with pytest.raises(ConfigError, match="action_delay"):  # a control period of 10 substeps
    load_config("asc-inc-cog-robust", ["control.period=0.1", "randomization.action_delay=[0, 25]"])
  # `period` is the task's own control period: 10 substeps at 0.1 s, 25 at the paper's 0.25 s
  short = load_config("asc-inc-cog-robust", ["control.period=0.1"])
  assert short.randomization.action_delay == (0, 10)
  assert scene_config(short, "hardest+latency-period").randomization.action_delay == (10, 10)
  assert scene_config(load_config("asc-inc-cog"), "hardest+latency-period").randomization.action_delay == (25, 25)
  case = scene_config(load_config("asc-inc-cog-robust", ["randomization.grow=true"]), "hardest+friction-low")
  r = case.randomization
  assert (r.enabled, r.grow, r.friction_along, r.mass, case.observation.noise) == (True, False, (0.8, 0.8), (1.0, 1.0), 0.0)


def test_servo_gain_and_damping_reach_the_model(jaguar_stairs):
  sim = jaguar_stairs
  p = jax.tree_util.tree_map(lambda x: x[0], _draws(load_config("asc-inc-cog-robust").randomization, n=1))
  p = p.replace(servo_gain=jnp.float32(0.5), joint_damping=jnp.float32(3.0))
  m = rnd.with_dynamics(sim.model, p, sim.layout.chassis_body, sim.layout.joint_qvel)
  np.testing.assert_allclose(np.asarray(m.actuator_gainprm[:, 0]), 0.5 * np.asarray(sim.model.actuator_gainprm[:, 0]))
  np.testing.assert_allclose(np.asarray(m.actuator_biasprm[:, 1:3]), 0.5 * np.asarray(sim.model.actuator_biasprm[:, 1:3]))
  damping = np.asarray(m.dof_damping)
  assert np.all(damping[sim.layout.joint_qvel] == 3.0) and np.all(np.delete(damping, sim.layout.joint_qvel) == 0.0)

"""The task environment: a Brax `Env` whose reset / step are pure functions of a typed state.

One control step: action -> low-level control -> physics substeps with the track model -> sensors
(IMU, pose, joints, depth beams) -> rewards (reward terms, termination, safety) -> observation.
The scene (staircase or navigation area) is data in the state, drawn at reset from the scene
sampler at difficulty eps; `reset_at(key, eps, penalty_k)` is what the curriculum wrapper calls.
"""

from __future__ import annotations

import copy
import dataclasses

import jax
import jax.numpy as jnp
from brax.envs.base import Env, State
from flax import struct
from mujoco import mjx

from mjx_tracks.envs.beams import BeamLayout, depth_beams
from mjx_tracks.envs.config import ConfigError, SceneConfig, TaskConfig
from mjx_tracks.envs.observations import Sensors, observe, part_sizes, stack
from mjx_tracks.envs import randomization as rnd
from mjx_tracks.envs.safety_filter import SafetyFilter
from mjx_tracks.envs.scan import ScanLayout, scan_ranges
from mjx_tracks.envs.rewards import Monitor, cog_deviation, goal_distance, normalizer_init, on_stairs
from mjx_tracks.metrics import STEP_NAMES as METRICS  # the per-step metrics (mjx_tracks.metrics.STEP)
from mjx_tracks.robots import get_robot
from mjx_tracks.sim import mjx_private
from mjx_tracks.sim.collisions import CollisionWatch, footprint_half
from mjx_tracks.sim.control import Controller
from mjx_tracks.sim.layout import BELT_SIDE
from mjx_tracks.sim.pose import chassis_rpy, chassis_velocity
from mjx_tracks.sim.simulator import Simulator, runs_late_command
from scenes.curriculum import Curriculum
from scenes.navigation import NavScene
from scenes.samplers import Draw
from scenes.scene import SceneState
from scenes.kinds import scene_kind
from scenes.staircase import StairScene, Staircase
from scenes.terrain import TerrainScene


@struct.dataclass
class EnvState:
  """Everything one environment carries between control steps."""

  data: mjx.Data
  scene: SceneState
  targets: jax.Array  # (n_joints,) rad, joint servo targets
  d0: jax.Array  # () m, starting goal distance (minus tolerance)
  closest: jax.Array  # () m, closest goal distance so far (reward.progress_form potential: the last one)
  window: jax.Array  # (safety_window,) last raw safety samples, newest first
  signal_sum: jax.Array  # () raw safety samples summed over the episode
  steps: jax.Array  # () int32 control steps taken in the episode
  penalty_sum: jax.Array  # () raw safety penalty summed over the episode
  penalty_k: jax.Array  # () global penalty normalization K
  collided: jax.Array  # () bool, the robot touched a wall or obstacle earlier in the episode
  key: jax.Array
  robust: rnd.RobustState | None = None  # the episode's randomization (None: randomization off)


PERIOD = "period"  # state.info key of a Period that step() takes instead of running the physics


@struct.dataclass
class Period:
  """One control period's command and physics (TrackedRobotEnv.period): what step() continues from."""

  data: mjx.Data  # after the period's substeps, before sensing
  collided: jax.Array  # () bool, the robot touched a wall or obstacle during the period
  robust: rnd.RobustState | None  # the randomization's state after the period (None: randomization off)
  belts: jax.Array  # (2,) m/s, the belt speeds the encoders read at the period's end
  targets: jax.Array  # (n_joints,) rad, the joints' servo targets of the command
  filtered: jax.Array  # () bool, the safety filter changed the command


def make_scene(s: SceneConfig) -> StairScene | NavScene | TerrainScene:
  """The scene generator of a task's scene section (its kind's, scenes.kinds)."""
  return scene_kind(s.kind).make(s)


class TrackedRobotEnv(Env):
  """Brax environment of one task; nothing on self changes after __init__."""

  def __init__(self, cfg: TaskConfig, every_path: bool = False):
    """every_path: compile every randomization path whatever cfg.randomization says, so that
    perturbations given to reset_at as data (the robustness suite) run in one program."""
    self.cfg = cfg
    self.robot = get_robot(cfg.robot)
    try:
      self.controller = Controller.create(self.robot, cfg.control.mode, cfg.control.increments,
                                          cfg.control.v_range, cfg.control.dof_curriculum)
    except ValueError as e:
      raise ConfigError(f"control: {e}") from e
    self.kind = scene_kind(cfg.scene.kind)
    self.scene = self.kind.make(cfg.scene)
    self.sim = Simulator.create(self.robot, self.scene.world_xml(), cfg.physics)
    self.watch = CollisionWatch.create(self.sim.mj_model, self.sim.layout, *self.kind.collision_geoms(self.scene))
    self.footprint = footprint_half(self.sim.mj_model, self.sim.layout.chassis_body)  # (m, m) half-sizes
    self.substeps = int(round(cfg.control.period / cfg.physics.timestep))
    o = cfg.observation
    self.beams = BeamLayout.create(
        self.robot.camera_hfov, self.robot.camera_resolution,
        o.vertical_beams if "vertical_beams" in o.parts else 0,
        o.horizontal_beams if "horizontal_beams" in o.parts else 0,
        o.band_px, o.rays_per_band, o.depth_range, self.robot.camera_range[1], o.noise)
    self.scan = ScanLayout(o.scan_rays if "scan" in o.parts else 0, o.scan_range, self.robot.lidar_pos,
                           tuple(o.scan_pitches))
    f = cfg.control.safety_filter
    self.safety = (SafetyFilter(ScanLayout(f.rays, o.scan_range, self.robot.lidar_pos, (0.0,)), self.footprint, f.horizon,
                                f.samples, f.margin, self.robot.max_speed, self.robot.max_yaw_rate, f.response, f.reverse)
                   if f.enabled else None)  # None: commands go to the belts as the policy gives them
    self.rand = cfg.randomization
    self.randomized = cfg.randomization.enabled or every_path  # the state carries a RobustState
    self.acting = frozenset(g for g in rnd.GROUPS if every_path or cfg.randomization.acts(g))  # costly paths compiled
    self.monitor = Monitor(cfg.reward, cfg.episode)
    self.task_draw = None  # scenes' draw where it replaces the task's (a view: for_task)
    c = cfg.scene.curriculum
    self.curriculum = Curriculum(window=c.window, rule=c.rule)
    self.part_sizes = part_sizes(o.parts, self.robot, self.beams.n_vertical, self.beams.n_horizontal,
                                 self.scan.size)

  def for_task(self, data) -> "TrackedRobotEnv":
    """This environment as one run of a program of several tasks sees it (data: its
    mjx_tracks.envs.task_data.TaskData): scenes from data.draw, the safety term of data.safety;
    a new object, this one unchanged."""
    view = copy.copy(self)
    view.task_draw, view.monitor = data.draw, dataclasses.replace(self.monitor, safety=data.safety)
    return view

  # --- Brax Env interface -------------------------------------------------------------------
  @property
  def observation_size(self) -> int:
    return sum(self.part_sizes.values()) * self.cfg.observation.history

  @property
  def action_size(self) -> int:
    return self.controller.action_size

  @property
  def backend(self) -> str:
    return "mjx"

  def reset(self, rng: jax.Array) -> State:
    return self.reset_at(rng, jnp.float32(self.curriculum.eps0), normalizer_init(self.cfg.reward).k)

  def step(self, state: State, action: jax.Array) -> State:
    period = state.info.get(PERIOD)  # run ahead by a program of its own (train.core.algos.ppo_split)
    return self._finish(state, self.period(state, action) if period is None else period)

  def period(self, state: State, action: jax.Array) -> Period:
    """The first part of step(state, action): the command and the control period's physics."""
    es: EnvState = state.pipeline_state
    m = self._model(es.scene, es.robust)
    v, w, targets = self.controller.decode(action, es.targets, state.info["eps"])
    v, w, filtered = self._safe_command(m, es, v, w)
    data, collided, robust, belts = self._advance(m, es, self.controller.belt_speeds(v, w), targets)
    return Period(data, collided, robust, belts, targets, filtered)

  def _finish(self, state: State, period: Period) -> State:
    """The rest of step(state, action) after its period: sensing, reward, termination, observation."""
    es: EnvState = state.pipeline_state
    m = self._model(es.scene, es.robust)
    collided, robust, belts, targets, filtered = (period.collided, period.robust, period.belts, period.targets,
                                                  period.filtered)
    data = self._sense(m, period.data)
    # a physics blow-up ends the episode and keeps the last finite state
    finite = jnp.all(jnp.isfinite(data.qpos)) & jnp.all(jnp.isfinite(data.qvel))
    data = jax.tree_util.tree_map(lambda a, b: jnp.where(finite, a, b), data, es.data)

    pos = data.xpos[self.sim.layout.chassis_body]
    rpy = chassis_rpy(data.qpos)
    dist = self._distance(pos, es.scene)
    collided = collided & finite
    cog, on_stairs = self._cog(data, es.scene)
    pitch_rate = jnp.abs(data.qvel[4])  # rad/s, chassis-frame pitch rate
    sample = self.monitor.safety_sample(cog, pitch_rate)
    window = jnp.roll(es.window, 1).at[0].set(sample)
    signal_sum, steps = es.signal_sum + sample, es.steps + 1
    rate = self.monitor.safety_rate(window, signal_sum, steps)
    terms, progress, closest, terminated, flags = self.monitor.evaluate(
        dist, es.closest, es.d0, rpy, rate, es.penalty_k, collided, self._clearance(pos, rpy[2], es.scene),
        self.watch.riding(data) if self.cfg.reward.riding_penalty else False)
    terms = {k: jnp.where(finite, t, 0.0) for k, t in terms.items()}
    terminated = terminated | ~finite
    key, k_obs = jax.random.split(es.key)
    es = es.replace(data=data, targets=targets, closest=closest, window=window, key=key, signal_sum=signal_sum,
                    steps=steps, penalty_sum=es.penalty_sum + self.monitor.safety_scale() * rate,
                    collided=es.collided | collided, robust=robust)
    # keys stay those of reset (wrappers may add their own): update values in place
    flags = {**flags, "first_collision": collided & ~state.pipeline_state.collided}
    metrics = {**state.metrics,
               **self._metrics(terms, progress * finite, cog, on_stairs, pitch_rate, flags, ~finite, filtered)}
    reward = sum(terms.values())
    return state.replace(pipeline_state=es, obs=self._obs(es, m, k_obs, state.obs, belts), reward=reward,
                         done=terminated.astype(jnp.float32), metrics=metrics)

  # --- the curriculum wrapper's reset -------------------------------------------------------
  def reset_at(self, rng: jax.Array, eps: jax.Array, penalty_k: jax.Array,
               perturbation: rnd.Perturbation | None = None, draw: Draw | None = None) -> State:
    """Draws a scene at difficulty eps and places the robot at its spawn; with randomization, the
    episode's perturbation is drawn too (or given). draw: the scene's sampler, ranges (and stair
    direction) as data (where the kind takes them: SceneKind.drawn), instead of the task's; default:
    a view's (for_task), else the task's own."""
    k_scene, k_obs, k_next = jax.random.split(rng, 3)
    draw = self.task_draw if draw is None else draw
    scene = self.scene.sample(k_scene, eps) if draw is None else self.scene.sample(k_scene, eps, draw)
    robust = None
    if self.randomized:  # its own stream: the paper's tasks draw as before
      p = perturbation if perturbation is not None else self.draw_perturbation(rng, eps)
      robust = rnd.RobustState(perturbation=p, belts=jnp.zeros(len(BELT_SIDE)))
    m = self._model(scene, robust)
    spawn, yaw, joints = self._start(scene, jax.random.fold_in(k_scene, 1))
    data = self._sense(m, self.sim.init_data(spawn, yaw, joints))
    d0 = self._distance(data.xpos[self.sim.layout.chassis_body], scene)
    es = EnvState(data=data, scene=scene, targets=joints, d0=d0, closest=d0,
                  window=jnp.zeros(self.cfg.reward.safety_window), signal_sum=jnp.float32(0.0),
                  steps=jnp.int32(0), penalty_sum=jnp.float32(0.0),
                  penalty_k=jnp.asarray(penalty_k, jnp.float32), collided=jnp.bool_(False), key=k_next,
                  robust=robust)
    zero = jnp.float32(0.0)
    metrics = {k: zero for k in METRICS}
    return State(pipeline_state=es, obs=self._obs(es, m, k_obs), reward=zero, done=zero,
                 metrics=metrics, info={"eps": jnp.asarray(eps, jnp.float32)})

  def draw_perturbation(self, rng: jax.Array, eps: jax.Array) -> rnd.Perturbation:
    """The draw of the task's randomization for the episode of reset key rng (the nominal robot where it is off)."""
    return rnd.task_draw(self.cfg, rng, eps, self.sim.layout.n_joints)

  # --- the physics of one control step ------------------------------------------------------
  def _model(self, scene: SceneState, robust: rnd.RobustState | None) -> mjx.Model:
    """The model of one environment: its scene's boxes, its episode's dynamics."""
    m = self.sim.with_boxes(scene.box_pos, scene.box_size, scene.box_yaw)
    if robust is not None and "model" in self.acting:
      m = rnd.with_dynamics(m, robust.perturbation, self.sim.layout.chassis_body, self.sim.layout.joint_qvel)
    return m

  def _advance(self, m: mjx.Model, es: EnvState, belts: jax.Array, targets: jax.Array):
    """(data, collided, robust state, belt speeds at the period's end: what the belts' encoders
    read, m/s) after one control period with the command (belt speeds m/s, joint targets rad); with
    randomization: belt gains and friction, a push, a late command and a jittered period
    (mjx_tracks.envs.randomization)."""
    data, n, late, robust = es.data, self.substeps, {}, es.robust
    ran = belts
    if robust is not None:
      p = robust.perturbation
      k_push, k_period = jax.random.split(jax.random.fold_in(es.key, 11))  # beside the paper's stream
      belts = ran = belts * rnd.belt_gains(p, BELT_SIDE)
      late["mu_scale"] = p.friction
      if "timing" in self.acting:
        late.update(held=(robust.belts, es.targets), delay=p.delay)
        n = rnd.period_substeps(p, self.substeps, k_period)
        ran = jnp.where(runs_late_command(n - 1, p.delay), robust.belts, belts)  # the period's last substep's
      if "push" in self.acting:
        data = data.replace(qvel=rnd.push(data.qvel, p, k_push)[0])
      robust = robust.replace(belts=belts)
    if self.watch.active:
      data, collided = self.sim.advance_watching(m, data, belts, targets, n, self.watch, **late)
    else:
      data, collided = self.sim.advance(m, data, belts, targets, n, **late), jnp.bool_(False)
    return data, collided, robust, ran

  def _safe_command(self, m: mjx.Model, es: EnvState, v: jax.Array, w: jax.Array):
    """(v m/s, w rad/s, whether the safety filter changed them): the command the belts get
    (mjx_tracks.envs.safety_filter), its ring read from the state the step starts from, with the
    episode's scan noise, and the chassis's velocity there (forward, sideways m/s, yaw rate rad/s in
    its own frame, as a state estimator would give it: the IMU noise of randomization not added)."""
    if self.safety is None:
      return v, w, jnp.bool_(False)
    return self.safety.choose(v, w, *self.safety_inputs(m, es))

  def safety_inputs(self, m: mjx.Model, es: EnvState) -> tuple[jax.Array, jax.Array]:
    """What the safety filter reads in state es: its ring's ranges (m) and the chassis's measured
    (forward m/s, sideways m/s, yaw rate rad/s) (_safe_command)."""
    p = None if es.robust is None else es.robust.perturbation
    d, body = es.data, self.sim.layout.chassis_body
    ranges = scan_ranges(self.safety.scan, m, d, body, jax.random.fold_in(es.key, 13),
                         None if p is None else p.depth_noise, None if p is None else p.hidden)
    velocity = chassis_velocity(d.xmat[body], d.qvel)  # m/s
    return ranges, jnp.stack([velocity[0], velocity[1], d.qvel[5]])  # qvel[5]: the yaw rate, chassis frame

  def _start(self, scene: SceneState, key: jax.Array) -> tuple[jax.Array, jax.Array, jax.Array]:
    """The robot's start: the scene's spawn (ground point, yaw) and joints at control.start_pose (0
    where it names none), each varied by scene.start_jitter (a_pos, a_yaw, a_joint): x, y ~ U(-a_pos,
    a_pos) m, yaw ~ + U(-a_yaw, a_yaw) rad, every joint ~ + U(-a_joint, a_joint) rad, clipped to its
    limits; the joints' servo targets start where the joints are."""
    nj = self.sim.layout.n_joints
    lim = jnp.asarray(self.controller.joint_limits, jnp.float32)
    pose = jnp.clip(self.robot.joint_vector(dict(self.cfg.control.start_pose)), lim[:, 0], lim[:, 1])
    a_pos, a_yaw, a_joint = self.cfg.scene.start_jitter
    if not (a_pos or a_yaw or a_joint):  # the paper's fixed start (and the same random stream as before)
      return scene.spawn_pos, scene.spawn_yaw, pose
    k_pos, k_yaw, k_joint = jax.random.split(key, 3)
    offset = jax.random.uniform(k_pos, (2,), minval=-a_pos, maxval=a_pos)
    spawn = scene.spawn_pos.at[:2].add(offset)
    yaw = scene.spawn_yaw + jax.random.uniform(k_yaw, minval=-a_yaw, maxval=a_yaw)
    joints = jnp.clip(pose + jax.random.uniform(k_joint, (nj,), minval=-a_joint, maxval=a_joint), lim[:, 0], lim[:, 1])
    return spawn, yaw, joints

  def _distance(self, pos: jax.Array, scene: SceneState) -> jax.Array:
    """The goal distance (m) minus the tolerance: straight, or (episode.distance geodesic) along the
    free-space path, straight where no such path exists (e.g. the robot pushed into an obstacle)."""
    straight = goal_distance(pos, scene.goal, scene.goal_halfwidth, self.cfg.episode.goal_tolerance)
    if self.cfg.episode.distance == "euclidean":
      return straight
    path = self.scene.free_space_distance(scene, pos) - self.cfg.episode.goal_tolerance
    return jnp.where(jnp.isfinite(path), path, straight)

  def _clearance(self, pos: jax.Array, yaw: jax.Array, scene: SceneState) -> jax.Array:
    """The footprint's distance (m) from the nearest wall where reward.clearance_penalty reads it, else inf."""
    if not self.cfg.reward.clearance_penalty:
      return jnp.float32(jnp.inf)
    return self.kind.clearance(self.scene, scene, pos, yaw, jnp.array(self.footprint, jnp.float32))

  # --- sensors ------------------------------------------------------------------------------
  def _sense(self, m: mjx.Model, d: mjx.Data) -> mjx.Data:
    """Positions, orientations and centre of mass consistent with the current qpos."""
    return mjx_private.kinematics(m, d)

  def _cog(self, d: mjx.Data, scene: SceneState) -> tuple[jax.Array, jax.Array]:
    """COG deviation (m) and whether the robot is on the stairs (1.0 / 0.0)."""
    if "cog_deviation" not in self.kind.signals:  # a staircase's incline defines it
      return jnp.float32(0.0), jnp.float32(0.0)
    st: Staircase = self.scene.stairs(scene.xi)
    body = self.sim.layout.chassis_body
    x = d.xpos[body][0]
    on = on_stairs(x, st.top_edge_x())
    dev = cog_deviation(d.subtree_com[body], d.xpos[body], jnp.arctan2(st.riser, st.tread))
    return jnp.where(on, dev, 0.0), on.astype(jnp.float32)

  def sensors(self, es: EnvState, m: mjx.Model, key: jax.Array, belts: jax.Array | None = None) -> Sensors:
    """Every reading an observation part may use (mjx_tracks.envs.observations); belts: the belt
    speeds at the end of the last control period (m/s, as _advance gives them; None: at rest, as at
    reset)."""
    d, r = es.data, es.robust
    real = {} if r is None else {"pitch": r.perturbation.camera_pitch, "range_noise": r.perturbation.depth_noise,
                                 "hidden": r.perturbation.hidden}
    beams = (depth_beams(self.beams, m, d, self.sim.layout.camera_site, key, **real)
             if self.beams.n_features else jnp.zeros(0))
    ranges = (scan_ranges(self.scan, m, d, self.sim.layout.chassis_body, jax.random.fold_in(key, 5),
                   real.get("range_noise"), real.get("hidden")) if self.scan.size else jnp.zeros(0))
    rot = d.xmat[self.sim.layout.chassis_body]
    rpy, rate, velocity, joints = chassis_rpy(d.qpos), d.qvel[3:6], chassis_velocity(rot, d.qvel), d.qpos[self.sim.layout.joint_qpos]
    if r is not None:  # what the robot's sensors read
      rpy, rate, velocity, joints = rnd.noisy_imu_and_joints(r.perturbation, rpy, rate, velocity, joints,
                                                             jax.random.fold_in(key, 3))
    return Sensors(linear_velocity=velocity, angular_velocity=rate, rpy=rpy, joints=joints,
                   position=d.qpos[0:3], goal=es.scene.goal,
                   vertical_beams=beams[: self.beams.n_vertical], horizontal_beams=beams[self.beams.n_vertical:],
                   scan=ranges, belts=jnp.zeros(len(BELT_SIDE)) if belts is None else belts)

  def _obs(self, es: EnvState, m: mjx.Model, key: jax.Array, previous: jax.Array | None = None,
           belts: jax.Array | None = None) -> jax.Array:
    """The policy's observation: this step's parts, after the previous observation's newer steps
    (observation.history; previous None at reset); belts as for sensors."""
    o = self.cfg.observation
    return stack(observe(o.parts, self.sensors(es, m, key, belts), self.robot), previous, o.history)

  def _metrics(self, terms, progress, cog, on_stairs, pitch_rate, flags, nan, filtered) -> dict[str, jax.Array]:
    f = lambda x: jnp.asarray(x, jnp.float32)
    out = {f"reward/{k}": f(v) for k, v in terms.items()}
    out.update(progress=f(progress), cog_deviation=f(cog), on_stairs=f(on_stairs),
               pitch_rate=f(pitch_rate), tipped_over=f(flags["tipped"]),
               goal_reached=f(flags["reached"]), moved_away=f(flags["away"]), physics_nan=f(nan),
               collision=f(flags["first_collision"]), command_filtered=f(filtered))
    assert tuple(out) == METRICS
    return out


def observation_names(env: TrackedRobotEnv) -> list[str]:
  """One name per observation entry, in order."""
  from mjx_tracks.envs.observations import observation_names as names  # noqa: PLC0415
  return names(env.cfg.observation.parts, env.part_sizes, env.cfg.observation.history)


__all__ = ["EnvState", "TrackedRobotEnv", "METRICS", "make_scene", "observation_names"]

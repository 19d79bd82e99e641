"""gate: the physics oracles under any physics settings (`--set physics.KEY=VALUE`), each figure
against its tolerance, PASS or FAIL (the command exits 1 on a failure): flat-ground speed and yaw
rate against the commanded ones, creep with the belts stopped on a 20-degree incline, the scripted
stair controller of both robots up and down the paper's hardest staircase, robot 1's single-step
limit (a step below the measured 0.275 m climbed, one far above it not), the contact culling along
those drives (every contact the C engine finds touching is kept, mjx_tracks.sim.culling), a passive fall
stepped by MJX under the settings against MuJoCo's C engine under the default ones, and no launch:
full throttle into the hardest staircase (nominal and low belt friction) never lifts the chassis
faster than its belts and speed can. A faster physics setting is adopted only if it passes.

    python -m train.bench gate --set physics.solver_iterations=2 --set physics.timestep=0.0125
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from train.bench.result import BenchInputError

CONTROL_PERIOD = 0.1  # s, of the scripted drives (as `python -m mjx_tracks.tools.drive`)
PAPER_TASK = "asc-inc-cog"  # whose hardest staircase the drives climb and descend (7 x 0.35 x 0.22 m)
FLAT_PERIOD, FALL_PERIOD = 0.25, 0.05  # s, between the flat / incline and the fall's samples
STEP_BELOW, STEP_ABOVE = 0.25, 0.35  # m, single steps below and far above robot 1's measured limit (0.275 m,
#                                      results/terrain/single-step-limit.json)
DRIVE_SECONDS = 20.0  # s, each scripted drive
FALL = dict(height=0.10, roll=0.25, seconds=1.5)  # m above resting, rad, s: the passive fall of the C-engine check
REFERENCE_ITERATIONS = 50  # solver and line-search iterations of the C engine's reference fall: converged
LAUNCH_SCENES = ("hardest", "hardest+friction-low")  # PAPER_TASK's evaluation scenes the launch check drives
#   into: nominal belt friction and the robustness suite's low friction (x0.8)
LAUNCH_TRIALS = 32  # full-throttle trials per scene (the evaluation's first 32: starts varied); what 3 and 4
#   solver iterations give: results/bench/gate/*.json, docs/benchmarks.md
GRAVITY = 9.81  # m/s^2


@dataclasses.dataclass(frozen=True)
class Check:
  name: str
  value: float
  limit: str  # the tolerance, as text: "<= 0.05", "reached", ...
  ok: bool
  unit: str = ""

  @staticmethod
  def at_most(name: str, value: float, bound: float, unit: str = "") -> "Check":
    """A figure that passes at or below its bound."""
    return Check(name, value, f"<= {bound:g}", value <= bound, unit)

  def row(self) -> dict:
    return {"check": self.name, "value": float(f"{float(self.value):.4g}"), "unit": self.unit, "tolerance": self.limit,
            "pass": bool(self.ok)}


def add_args(p) -> None:
  p.add_argument("--set", action="append", default=[], metavar="physics.KEY=VALUE",
                 help="physics settings to check (configs/defaults.yaml's physics section)")
  p.add_argument("--robots", default="1,2", help="robots whose stair drives are checked")
  p.add_argument("--launch-trials", type=int, default=LAUNCH_TRIALS,
                 help=f"full-throttle trials per scene of the launch check (default {LAUNCH_TRIALS})")


def physics_of(overrides: list[str]):
  """The physics section under the overrides; only physics.* keys, and timesteps that divide the
  sampling periods (BenchInputError otherwise)."""
  from mjx_tracks.envs.config import ConfigError, load_config  # noqa: PLC0415
  wrong = [o for o in overrides if not o.startswith("physics.")]
  if wrong:
    raise BenchInputError(f"the gate checks physics settings only (physics.KEY=VALUE); got {', '.join(wrong)}")
  try:
    physics = load_config(PAPER_TASK, tuple(overrides)).physics
  except ConfigError as e:
    raise BenchInputError(str(e)) from None
  periods = (FALL_PERIOD, FLAT_PERIOD)
  if any(abs(p / physics.timestep - round(p / physics.timestep)) > 1e-6 for p in periods):
    raise BenchInputError(f"physics.timestep {physics.timestep} s must divide {periods} s (e.g. 0.005, 0.01, 0.0125)")
  return physics


def _substeps(physics, period: float) -> int:
  """Physics steps in `period` seconds (physics_of checked that the timestep divides it)."""
  return round(period / physics.timestep)


def _paper_hardest() -> tuple[float, float, int]:
  """(tread m, riser m, steps) of PAPER_TASK's hardest staircase: each range at its hard end."""
  from mjx_tracks.envs.config import load_config  # noqa: PLC0415
  from scenes.terrain_kinds import STAIRS  # noqa: PLC0415
  scene = load_config(PAPER_TASK).scene
  tread, riser, steps = STAIRS.hardest(lambda n: getattr(scene, n))
  return float(tread), float(riser), int(steps)


def flat_checks(physics) -> list[Check]:
  """Robot 1 on flat ground: steady speed at 0.5 m/s commanded, lateral drift, and yaw rate at
  0.5 rad/s commanded (the steering formula's) while turning in place."""
  import jax.numpy as jnp  # noqa: PLC0415

  from mjx_tracks.robots import get_robot  # noqa: PLC0415
  from mjx_tracks.sim.control import command_belt_speeds  # noqa: PLC0415
  from mjx_tracks.sim.pose import chassis_rpy  # noqa: PLC0415
  from mjx_tracks.sim.simulator import staircase_simulator  # noqa: PLC0415
  sim = staircase_simulator(get_robot(1), physics)
  r = sim.robot
  qpos = _drive_flat(sim, command_belt_speeds(0.5, 0.0, r.track_separation, r.steering_efficiency, r.max_speed), 12)
  speed = (qpos[-1, 0] - qpos[3, 0]) / (8 * FLAT_PERIOD)  # m/s over the last 2 s
  belts = command_belt_speeds(0.0, 0.5, r.track_separation, r.steering_efficiency, r.max_speed)
  turn = _drive_flat(sim, belts, 8)
  yaw = np.unwrap(np.asarray(chassis_rpy(jnp.asarray(turn)))[:, 2])
  rate = (yaw[-1] - yaw[3]) / (4 * FLAT_PERIOD)
  expected = r.steering_efficiency * float(belts[1] - belts[0]) / r.track_separation
  return [Check.at_most("flat speed error", abs(speed / 0.5 - 1), 0.05),
          Check.at_most("flat lateral drift", abs(qpos[-1, 1]), 0.02, "m"),
          Check.at_most("yaw rate error", abs(rate / expected - 1), 0.10),
          Check.at_most("turn-in-place drift", np.linalg.norm(turn[-1, :2]), 0.05, "m")]


def _drive_flat(sim, belts, periods: int) -> np.ndarray:
  """qpos after each of `periods` FLAT_PERIOD periods of constant belt speeds on the stair world's floor."""
  import jax  # noqa: PLC0415
  import jax.numpy as jnp  # noqa: PLC0415

  from scenes import staircase as sc  # noqa: PLC0415
  m = sim.with_boxes(*sc.step_boxes(sc.Staircase(jnp.float32(0.3), jnp.float32(0.17), jnp.int32(0))))
  nj, substeps = sim.layout.n_joints, _substeps(sim.physics, FLAT_PERIOD)
  adv = jax.jit(lambda d, belts: sim.advance(m, d, belts, jnp.zeros(nj), substeps))  # one program for every command
  d, out = sim.init_data(jnp.zeros(3), jnp.float32(0.0), jnp.zeros(nj)), []
  for _ in range(periods):
    d = adv(d, belts)
    out.append(np.asarray(d.qpos))
  return np.stack(out)


def incline_check(physics) -> list[Check]:
  """Robot 1 with its belts stopped on a 20-degree incline, nose up: creep over 5 s after 1 s of
  settling."""
  import jax  # noqa: PLC0415
  import jax.numpy as jnp  # noqa: PLC0415

  from mjx_tracks.robots import get_robot  # noqa: PLC0415
  from mjx_tracks.sim.simulator import Simulator  # noqa: PLC0415
  from scenes.world import world_geom_attrs  # noqa: PLC0415
  angle = math.radians(20)
  n = (-math.sin(angle), 0.0, math.cos(angle))
  world = f'<geom name="slope" type="plane" size="0 0 1" zaxis="{n[0]} {n[1]} {n[2]}" {world_geom_attrs()}/>'
  sim = Simulator.create(get_robot(1), world, physics)
  nj = sim.layout.n_joints
  d = sim.init_data(jnp.zeros(3), jnp.float32(0.0), jnp.zeros(nj))
  quat = jnp.array([math.cos(-angle / 2), 0.0, math.sin(-angle / 2), 0.0])
  d = d.replace(qpos=d.qpos.at[:3].set((sim.robot.spawn_height + 0.002) * jnp.asarray(n)).at[3:7].set(quat))
  substeps = _substeps(physics, FLAT_PERIOD)
  adv = jax.jit(lambda d: sim.advance(sim.model, d, jnp.zeros(6), jnp.zeros(nj), substeps))
  for _ in range(round(1.0 / FLAT_PERIOD)):  # settle 1 s
    d = adv(d)
  start = np.asarray(d.qpos[:3])
  for _ in range(round(5.0 / FLAT_PERIOD)):  # 5 s
    d = adv(d)
  creep = float(np.linalg.norm(np.asarray(d.qpos[:3]) - start))
  return [Check.at_most("creep on 20-degree incline in 5 s", creep, 0.01, "m")]


def stair_checks(physics, robot: str) -> list[Check]:
  """The scripted controller up and down the hardest staircase (goal reached, no tip-over); for
  robot 1 also the single steps below and far above its limit."""
  import jax.numpy as jnp  # noqa: PLC0415

  from mjx_tracks.envs.config import default_config  # noqa: PLC0415
  from mjx_tracks.robots import get_robot  # noqa: PLC0415
  from mjx_tracks.sim.simulator import staircase_simulator  # noqa: PLC0415
  from mjx_tracks.tools.drive import DriveSetup, scripted_rollouts, summarize  # noqa: PLC0415
  from scenes import staircase as sc  # noqa: PLC0415
  sim, tol = staircase_simulator(get_robot(robot), physics), default_config().episode.goal_tolerance
  hardest, out = _paper_hardest(), []
  for direction in ("up", "down"):
    cases = [("hardest", *hardest)] + ([("step", hardest[0], STEP_BELOW, 1), ("step", hardest[0], STEP_ABOVE, 1)]
                                       if robot == "1" and direction == "up" else [])
    stairs = sc.Staircase(*(jnp.asarray([c[i] for c in cases], t) for i, t in
                            ((1, jnp.float32), (2, jnp.float32), (3, jnp.int32))))
    setup = DriveSetup(sim, stairs, direction, CONTROL_PERIOD, tol)
    qpos = scripted_rollouts(setup, round(DRIVE_SECONDS / CONTROL_PERIOD))
    for (what, tread, riser, steps), q in zip(cases, qpos):
      s = summarize(dataclasses.replace(setup, stairs=sc.Staircase(tread, riser, steps)), q)
      passed = s["goal_reached"] and not s["tipped_over"]
      if what == "hardest":
        out.append(Check(f"robot {robot} scripted {direction} hardest staircase", passed, "reached", passed))
        from mjx_tracks.sim.culling import culling_figures  # noqa: PLC0415
        out += culling_checks(physics, culling_figures(sim, sc.Staircase(tread, riser, steps), q),
                              f"robot {robot} {direction}")
      else:
        want = riser == STEP_BELOW
        out.append(Check(f"robot {robot} scripted single step {riser} m", passed,
                         "climbed" if want else "not climbed", passed == want))
  return out


def culling_checks(physics, figures: tuple[int, int], what: str) -> list[Check]:
  """Along a drive whose culling figures (mjx_tracks.sim.culling.culling_figures) are given, the C
  engine's touching contacts fit physics.contact_slots and its touching belt-box pairs are among the
  physics.box_pairs MJX tests; -1 keeps all (nothing to check)."""
  most, worst = figures
  out = []
  if physics.contact_slots > 0:
    out.append(Check.at_most(f"{what}: most touching contacts (C engine)", most, physics.contact_slots))
  if physics.box_pairs > 0:
    out.append(Check.at_most(f"{what}: worst touching belt-box pair rank (C engine, 0-based)", worst,
                             physics.box_pairs - 1))
  return out


def c_engine_check(physics) -> list[Check]:
  """Robot 1 falling from FALL['height'] with roll FALL['roll'] onto the floor, joints held, belts
  still: MJX (no track model) under the settings against MuJoCo's C engine under the defaults with
  REFERENCE_ITERATIONS solver and line-search iterations (a converged reference that does not move
  with the defaults); the largest height and roll / pitch differences over the fall."""
  import jax  # noqa: PLC0415
  import jax.numpy as jnp  # noqa: PLC0415
  import mujoco  # noqa: PLC0415

  from mjx_tracks.envs.config import default_config  # noqa: PLC0415
  from mjx_tracks.robots import get_robot  # noqa: PLC0415
  from mjx_tracks.sim.physics import compile_model  # noqa: PLC0415
  from mjx_tracks.sim.pose import chassis_rpy  # noqa: PLC0415
  from mjx_tracks.sim.simulator import staircase_simulator  # noqa: PLC0415
  from scenes import staircase as sc  # noqa: PLC0415
  sim = staircase_simulator(get_robot(1), physics)
  reference = dataclasses.replace(default_config().physics, solver_iterations=REFERENCE_ITERATIONS,
                                  ls_iterations=REFERENCE_ITERATIONS)
  mj = compile_model(sim.robot, sc.world_xml(), reference)  # the C engine's reference model
  d = sim.init_data(jnp.zeros(3), jnp.float32(0.0), jnp.zeros(sim.layout.n_joints))
  quat = [math.cos(FALL["roll"] / 2), math.sin(FALL["roll"] / 2), 0.0, 0.0]
  qpos0 = np.asarray(d.qpos).copy()
  qpos0[2] += FALL["height"]
  qpos0[3:7] = quat
  chunks, substeps = round(FALL["seconds"] / FALL_PERIOD), _substeps(physics, FALL_PERIOD)
  step = jax.jit(lambda d: jax.lax.fori_loop(0, substeps, lambda _, x: sim.plain_step(sim.model, x), d))
  d, ours = d.replace(qpos=d.qpos.at[:].set(qpos0)), []  # on the device, as step's output: one compilation
  for _ in range(chunks):
    d = step(d)
    ours.append(np.asarray(d.qpos))
  c = mujoco.MjData(mj)
  c.qpos[:] = qpos0
  theirs = []
  for _ in range(chunks):
    mujoco.mj_step(mj, c, nstep=round(FALL_PERIOD / mj.opt.timestep))
    theirs.append(c.qpos.copy())
  ours, theirs = np.stack(ours), np.stack(theirs)
  dz = float(np.abs(ours[:, 2] - theirs[:, 2]).max())
  rpy = [np.asarray(chassis_rpy(jnp.asarray(q))) for q in (ours, theirs)]
  dang = float(np.abs(rpy[0][:, :2] - rpy[1][:, :2]).max())
  return [Check.at_most("fall vs C engine: height", dz, 0.005, "m"),
          Check.at_most("fall vs C engine: roll / pitch", dang, 0.02, "rad")]


def launch_bound(robot, period: float) -> float:
  """The most a chassis can rise in one control period (m): its belts lift it at most max_speed x
  period (straight up a wall), and a jump off its speed at most max_speed^2 / 2g higher."""
  return robot.max_speed * period + robot.max_speed ** 2 / (2 * GRAVITY)


def largest_rises(cfg, scene: str, trials: int) -> np.ndarray:
  """Each trial's largest rise of the chassis in one control step (m) while its episode lasts, full
  throttle (the `full` baseline) on evaluation scene `scene` of task cfg."""
  from mjx_tracks.baselines import baseline  # noqa: PLC0415
  from train.evaluation import largest_per_trial  # noqa: PLC0415

  def rise(before, after):
    return after.pipeline_state.data.qpos[:, 2] - before.pipeline_state.data.qpos[:, 2]
  return largest_per_trial(cfg, scene, baseline("full").make, rise, trials)


def launch_check(physics, scenes=LAUNCH_SCENES, trials: int = LAUNCH_TRIALS) -> list[Check]:
  """Full throttle into PAPER_TASK's hardest staircase (each of `scenes`): the chassis's largest
  rise in one control step against launch_bound. A solver that has not converged throws the robot
  up when it meets the first riser (3 Newton iterations do: docs/benchmarks.md)."""
  from mjx_tracks.envs.config import load_config  # noqa: PLC0415
  from mjx_tracks.robots import get_robot  # noqa: PLC0415
  cfg = dataclasses.replace(load_config(PAPER_TASK), physics=physics)
  bound = launch_bound(get_robot(cfg.robot), cfg.control.period)
  out = []
  for scene in scenes:
    rises = largest_rises(cfg, scene, trials)
    out.append(Check.at_most(f"largest rise in one control step, full throttle, {scene} "
                             f"({int((rises > bound).sum())} of {trials} trials above)", float(rises.max()), bound, "m"))
  return out


def run(args) -> tuple[list[dict], dict]:
  physics = physics_of(args.set)
  if args.launch_trials < 1:
    raise BenchInputError(f"--launch-trials must be at least 1, got {args.launch_trials}")
  checks = flat_checks(physics) + incline_check(physics) + c_engine_check(physics)
  checks += launch_check(physics, trials=args.launch_trials)
  for robot in args.robots.split(","):
    checks += stair_checks(physics, robot.strip())
  rows = [c.row() for c in checks]
  for r in rows:
    print(f"{'PASS' if r['pass'] else 'FAIL'}  {r['check']}: {r['value']:g} {r['unit']} (tolerance {r['tolerance']})",
          flush=True)
  verdict = all(r["pass"] for r in rows)
  print(f"gate: {'PASS' if verdict else 'FAIL'} for {dataclasses.asdict(physics)}", flush=True)
  return rows, {"physics": dataclasses.asdict(physics), "overrides": list(args.set), "pass": verdict}

"""The metrics schema: every per-step, per-episode and report metric, declared once.

The env's `state.metrics` (STEP), each episode's or evaluation trial's figures (EPISODE; one
definition of success), and the columns of training reports (REPORT: the database's `stats`
table, the dashboard's curves, study figures) are read from here: the env, episode statistics,
the database, evaluation reports, the API, the dashboard and study reports.
"""

from __future__ import annotations

import dataclasses

import numpy as np


@dataclasses.dataclass(frozen=True)
class Metric:
  name: str
  unit: str  # "" for a count, a flag or a fraction
  aggregate: str  # how it reduces: "sum" (over an episode's steps), "mean", "rate" (of a 0/1 flag), "last"
  higher_is_better: bool | None  # None: neither (a diagnostic)
  meaning: str
  integer: bool = False  # stored as an integer (a flag or a count)


REWARD_TERMS = ("progress", "safety", "tipover", "goal", "collision", "clearance", "riding")  # the reward's named terms (mjx_tracks.envs.rewards)

# per control step: the env's state.metrics, in this order; summed over an episode by Brax's
# episode wrapper and by evaluation (EPISODE figures are made from those sums)
STEP = (
    *(Metric(f"reward/{t}", "", "sum", True, f"the reward's {t} term (scaled)") for t in REWARD_TERMS),
    Metric("progress", "", "sum", True, "fraction of the starting goal distance covered at this step"),
    Metric("cog_deviation", "m", "sum", False, "COG deviation from the incline (0 off the stairs; stairs only)"),
    Metric("on_stairs", "", "sum", None, "1 while the chassis is over the staircase (stairs only)"),
    Metric("pitch_rate", "rad/s", "sum", False, "|pitch angular velocity| of the chassis"),
    Metric("tipped_over", "", "sum", False, "1 at the step the robot tips over (|roll| or |pitch| > pi/2)"),
    Metric("goal_reached", "", "sum", True, "1 at the step the robot reaches the goal (it ends the episode)"),
    Metric("moved_away", "", "sum", False, "1 at the step the robot ends too far from the goal"),
    Metric("physics_nan", "", "sum", False, "1 at a step whose physics blew up (the episode ends)"),
    Metric("collision", "", "sum", False, "1 at the episode's first step in which the robot touched a wall or "
           "obstacle (nav scenes; a floor obstacle: with anything but a track belt); reward/collision charges every one"),
    Metric("command_filtered", "", "sum", None, "1 at a step whose command the safety filter slowed "
           "(control.safety_filter; nav scenes)"),
)
STEP_NAMES = tuple(m.name for m in STEP)

# per episode (an evaluation trial, or a training episode): from the sums of the STEP metrics
EPISODE = (
    Metric("progress", "", "mean", True, "fraction of the starting goal distance covered (0..1)"),
    Metric("success", "", "rate", True, "the goal was reached (the step that reaches it ends the episode)", True),
    Metric("cog_deviation", "m", "mean", False, "mean COG deviation while on the stairs (stairs only)"),
    Metric("pitch_rate", "rad/s", "mean", False, "mean |pitch rate| over the episode"),
    Metric("tipped_over", "", "rate", False, "the robot tipped over", True),
    Metric("length", "steps", "mean", None, "control steps the episode lasted", True),
    Metric("collided", "", "rate", False, "the robot touched a wall or obstacle at least once (nav scenes)", True),
    Metric("filtered", "", "mean", None, "fraction of the episode's control steps whose command the safety filter "
           "slowed (control.safety_filter)"),
)
EPISODE_NAMES = tuple(m.name for m in EPISODE)
BY_NAME = {m.name: m for m in EPISODE}

# a training report's columns (database table `stats`): each episode figure's mean over the
# episodes of a report, named by how it aggregates; `return_mean` and `eps` besides
REPORT_COLUMN = {"progress": "progress_mean", "cog_deviation": "cog_deviation_mean", "pitch_rate": "pitch_rate_mean",
                 "tipped_over": "tipped_rate", "success": "success_rate",
                 "collided": "collision_rate"}
REPORT = (Metric("return_mean", "", "mean", True, "mean return of the episodes of the report"),
          *(dataclasses.replace(BY_NAME[n], name=c) for n, c in REPORT_COLUMN.items()),
          Metric("eps", "", "last", True, "the curriculum's difficulty"))
REPORT_NAMES = tuple(m.name for m in REPORT)


def success(goal_reached_sum) -> np.ndarray:
  """The one definition of success, from the episode's sum of `goal_reached`: the goal was reached."""
  return (np.asarray(goal_reached_sum, np.float64) > 0).astype(np.float64)


def timed_out(figures: dict) -> np.ndarray:
  """The one definition of a trial that ran out of time, from its EPISODE figures (arrays of trials):
  it neither reached the goal, touched a wall or obstacle (`collided`) nor tipped over. (A trial that
  collided and went on, where a collision does not end the episode, is counted as collided.)"""
  reached, hit, tipped = (np.asarray(figures[k], np.float64) > 0 for k in ("success", "collided", "tipped_over"))
  return ~reached & ~hit & ~tipped


def trajectory_success(reached, tipped) -> bool:
  """success() of a trajectory cut where the tasks end an episode: at the first step that reaches
  the goal or tips over (reached, tipped: per-step 0/1 flags)."""
  reached, tipped = np.asarray(reached, bool), np.asarray(tipped, bool)
  ends = np.flatnonzero(reached | tipped)
  return bool(success(reached[: ends[0] + 1].sum())) if ends.size else False


def episode_figures(sums: dict, length) -> dict[str, np.ndarray]:
  """The EPISODE figures from `sums` (each STEP metric summed over the episode) and the episode's
  length in control steps."""
  f = lambda k: np.asarray(sums[k], np.float64)  # noqa: E731
  length = np.asarray(length, np.float64)
  on = f("on_stairs")
  figures = {
      "progress": f("progress"),
      "success": success(f("goal_reached")),
      "cog_deviation": np.where(on > 0, f("cog_deviation") / np.maximum(on, 1e-9), 0.0),  # m, on the stairs
      "pitch_rate": f("pitch_rate") / np.maximum(length, 1.0),  # rad/s, mean |pitch rate|
      "tipped_over": (f("tipped_over") > 0).astype(np.float64),
      "length": length,
      "collided": (f("collision") > 0).astype(np.float64),
      "filtered": f("command_filtered") / np.maximum(length, 1.0),
  }
  assert tuple(figures) == EPISODE_NAMES
  return figures


def trial_row(figures: dict, i: int) -> dict:
  """Trial i's EPISODE figures as a database row: integers where the metric is one."""
  return {m.name: (int(figures[m.name][i] > 0) if m.aggregate == "rate" else int(figures[m.name][i])) if m.integer
          else float(figures[m.name][i]) for m in EPISODE}

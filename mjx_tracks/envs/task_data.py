"""Runs of several tasks in one compiled program (`python -m train.run --tasks A,B --seeds ...`):
what such runs may differ in, as data. The paper's four stair tasks differ only in the stair
direction, the sampler and the reward kind: a program builds the environment of its first run's
config and gives each run a view of it (TrackedRobotEnv.for_task) that reads the run's TaskData,
its scene draw (the kind's `drawn` keys, scenes.samplers.Draw: sampler, ranges, stair direction)
and its reward's safety term (mjx_tracks.envs.rewards.Safety). A run's state has the shapes of the
same run alone, so each resumes alone (`--resume`) with its own config, where those are static."""

from __future__ import annotations

import jax
import jax.numpy as jnp
from flax import struct

from mjx_tracks.envs.config import TaskConfig
from mjx_tracks.envs.rewards import Safety, safety_of
from scenes.kinds import scene_kind
from scenes.samplers import Draw

REWARD_KEYS = ("reward.kind", "reward.cog_scale", "reward.angular_scale")  # Safety's
SCENE_KEYS = ("direction", "sampler")  # of a kind's `drawn` keys, those that change no array's shape


@struct.dataclass
class TaskData:
  """One run's task as data in a program of several tasks."""
  draw: Draw | None  # its scenes' draw (None: the kind takes none, the program's own scenes)
  safety: Safety  # its reward's safety term


def packed_keys(cfg: TaskConfig) -> tuple[str, ...]:
  """The config keys (dotted) in which runs of one program may differ: the task's name, its
  reward's safety term and the scene keys of SCENE_KEYS its kind draws as data."""
  drawn = scene_kind(cfg.scene.kind).drawn
  return ("task", *REWARD_KEYS, *(f"scene.{k}" for k in SCENE_KEYS if k in drawn))


def _flat(d: dict, prefix: str = "") -> dict:
  out = {}
  for k, v in d.items():
    out.update(_flat(v, f"{prefix}{k}.") if isinstance(v, dict) else {f"{prefix}{k}": v})
  return out


def packing_conflict(cfg: TaskConfig, other: TaskConfig) -> str | None:
  """The first key (dotted) in which two runs' configs differ that no program can take as data;
  None where the runs may train in one program."""
  a, b, allowed = _flat(cfg.to_dict()), _flat(other.to_dict()), set(packed_keys(cfg))
  return next((k for k in sorted(a.keys() | b.keys()) if a.get(k) != b.get(k) and k not in allowed), None)


def task_data(cfg: TaskConfig, program: TaskConfig) -> TaskData:
  """Run config cfg's task as data for the environment of config `program` (one that cfg may share
  a program with: packing_conflict None)."""
  return TaskData(scene_kind(program.scene.kind).draw(cfg.scene, program.scene), safety_of(cfg.reward))


def stacked(datas: list[TaskData]) -> TaskData:
  """The runs' task data with a leading run axis (the program's vmap)."""
  return jax.tree_util.tree_map(lambda *x: jnp.stack(x), *datas)

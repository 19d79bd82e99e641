"""Building a run's parts from its plan: the batched environment, the learner, the device mesh
and the state's shardings, the compiled update, the evaluator."""

from __future__ import annotations

import copy
import dataclasses
import functools
import hashlib
import json
import sys
import time
from typing import Any, Callable

import jax
from jax.sharding import NamedSharding, PartitionSpec

from mjx_tracks import compile_cache
from mjx_tracks.envs.task_env import TrackedRobotEnv
from mjx_tracks.envs.wrappers import batched_env
from train.core.algos.ppo import PPO, ppo_layout
from train.core.algos.ppo_split import SplitUpdate
from train.core.algos.sac import SAC
from train.evaluation import scene_config
from train.core.mesh import BATCH, ShardedStep, make_mesh, replicated, state_shardings, use_gspmd_partitioner
from train.core.networks import NetworkSpec


@dataclasses.dataclass(frozen=True)
class Training:
  """A run's built parts."""
  plan: Any  # train.core.plan.RunPlan
  mesh: Any
  core: TrackedRobotEnv
  learner: PPO | SAC
  spec: NetworkSpec
  abstract: Any  # the learner state's shapes and dtypes (jax.ShapeDtypeStruct tree)
  shardings: Any  # the learner state's shardings
  note: str | None  # how the preset was adapted to --num-envs, if it was


def network_spec(plan, core: TrackedRobotEnv) -> NetworkSpec:
  p = plan.preset
  hidden = (p.policy_hidden, p.value_hidden) if plan.algo == "ppo" else (p.hidden, p.hidden)
  return NetworkSpec(plan.algo, core.observation_size, core.action_size, *hidden)


def build(plan, mesh=None) -> Training:
  """The environment, learner and shardings of a plan (nothing is compiled yet)."""
  use_gspmd_partitioner()
  mesh = make_mesh() if mesh is None else mesh
  core = TrackedRobotEnv(plan.cfg)
  env = training_env(core, mesh)
  spec = network_spec(plan, core)
  note = None
  if plan.algo == "ppo":
    layout = ppo_layout(plan.preset, plan.num_envs, mesh.devices.size)
    learner = PPO(env, spec.build(), plan.preset, layout, NamedSharding(mesh, PartitionSpec(None, BATCH)))
    note = layout.note
  else:
    learner = SAC(env, spec.build(), plan.preset, plan.num_envs)
  abstract = jax.eval_shape(learner.init, jax.random.PRNGKey(0))
  return Training(plan, mesh, core, learner, spec, abstract, state_shardings(abstract, mesh), note)


def training_env(core: TrackedRobotEnv, mesh):
  """The batched environment a learner trains on: each device steps its own robots."""
  return ShardedStep(batched_env(core, axis_name=BATCH), mesh)


def learner_on(t: Training, data):
  """t's learner on the view of its environment that run data (mjx_tracks.envs.task_data.TaskData)
  sees, in a program of several tasks (a copy: t's learner unchanged)."""
  other = copy.copy(t.learner)
  other.env = training_env(t.core.for_task(data), t.mesh)
  return other


def init_state(t: Training, seed: int):
  """A fresh learner state, laid out on the mesh."""
  return jax.jit(t.learner.init, out_shardings=t.shardings)(jax.random.PRNGKey(seed))


def shaped_state(t: Training):
  """The learner state as shapes, dtypes and shardings (what the update is compiled for)."""
  return jax.tree_util.tree_map(lambda a, s: jax.ShapeDtypeStruct(a.shape, a.dtype, sharding=s),
                                t.abstract, t.shardings)


def compile_update(t: Training, stream=None, meanwhile: Callable[[], None] = lambda: None, split: bool = False):
  """(the update compiled ahead of time with the state donated, the seconds that took); says
  beforehand how long it should take (on stream, default: sys.stdout as it is at the call).
  meanwhile(): called once the update is lowered, while XLA compiles it (train.core.ahead.start).
  split: PPO's update as programs compiled side by side (train.core.algos.ppo_split)."""
  stream = stream or sys.stdout  # not the one at import: a caller may have redirected it since
  config = hashlib.sha1(json.dumps(t.plan.cfg.to_dict(), sort_keys=True).encode()).hexdigest()[:8]
  what = (f"{t.plan.task}/{config}/{t.plan.algo}/{t.plan.preset_name}/{t.plan.num_envs} envs/"
          f"{t.mesh.devices.size} x {jax.default_backend()}{'/split' if split else ''}")
  last = compile_cache.last_compile_seconds(what)
  guess = f"up to ~{last:,.0f} s" if last is not None else "a minute or more the first time"
  print(f"compiling the training step ({guess}; the compilation cache makes later runs faster) ...",
        file=stream, flush=True)
  t0 = time.time()
  shaped = shaped_state(t)
  if split:
    compiled = SplitUpdate(t.learner, t.core, t.mesh, t.shardings).compile(shaped, meanwhile, stream)
  else:
    jitted = jax.jit(t.learner.update, in_shardings=(t.shardings,),
                     out_shardings=(t.shardings, replicated(t.mesh)), donate_argnums=0)
    lowered = jitted.lower(shaped)
    meanwhile()
    compiled = lowered.compile()
  seconds = time.time() - t0
  compile_cache.record_compile_seconds(what, seconds)  # kept only if the longest yet
  print(f"compiled in {seconds:,.0f} s", file=stream, flush=True)
  return compiled, seconds


def has_evaluations(t: Training) -> bool:
  """Whether the run's preset asks for Brax's evaluator (its eval/... reports) between updates."""
  p = t.plan.preset
  return bool(getattr(p, "run_evals", True) and p.num_evals >= 2)


def eval_env(t: Training):
  """The batched environment Brax's evaluator plays: uniform scenes over the task's ranges."""
  return batched_env(eval_core(t))


def eval_core(t: Training) -> TrackedRobotEnv:
  """The environment of Brax's evaluator's episodes, unbatched."""
  return TrackedRobotEnv(eval_config(t.plan.cfg))


def eval_config(cfg):
  """The task config of Brax's evaluator's episodes (train.evaluation's uniform scene)."""
  return scene_config(cfg, "uniform")


def brax_evaluator(t: Training, seed: int):
  """Brax's evaluator of a run of seed `seed`: num_eval_envs episodes of eval_env, deterministic policy."""
  from brax.training import acting  # noqa: PLC0415
  return acting.Evaluator(eval_env(t), functools.partial(t.learner.make_policy, deterministic=True),
                          num_eval_envs=t.plan.preset.num_eval_envs, episode_length=t.plan.cfg.episode.max_steps,
                          action_repeat=1, key=eval_key(seed))


def eval_key(seed: int):
  """The key Brax's evaluator of a run of seed `seed` starts from."""
  return jax.random.PRNGKey(seed + 1)


def make_evaluator(t: Training, seed: int):
  """Brax's evaluator (brax_evaluator), or None when the preset has none."""
  return brax_evaluator(t, seed) if has_evaluations(t) else None

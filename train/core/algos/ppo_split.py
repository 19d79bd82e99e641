"""PPO's update (train.core.algos.ppo) as five programs that XLA compiles side by side, the env
steps of its unrolls a loop on the host: `keys`, then for each env step `act` (the policy and the
control period's physics: MJX's substep loop), `finish` (the rest of the env step: sensing, reward,
the curriculum's update) and `reset` (new episodes where theirs ended; the step's transition), then
`learn` (normalizer update, SGD epochs).

Why: XLA compiles a program on one thread, so the fused update's compilation is the sum of its
parts, the physics loop about half of it (scripts/analysis/program_size.py --compile). Compiled
apart and at once, the update is ready after its longest parts (docs/benchmarks.md, "PPO's update as
programs side by side"). The price: 3 dispatches an env step (the `gpu` preset's update is 20 env
steps) and no fusion across the cuts.

It computes what PPO.update computes from the same state (the same keys in the same order;
tests/test_ppo_split.py compares them), for a run of one task; a program of several runs
(train.core.group) keeps the fused update, and so does SAC.
"""

from __future__ import annotations

import concurrent.futures
import functools
import gc
import time
from typing import Callable

import jax
import jax.numpy as jnp
import numpy as np
from brax.training import acting

from mjx_tracks.envs.task_env import PERIOD, TrackedRobotEnv
from train.core.algos.ppo import PPO, STATE_EXTRAS, PPOState, batch_major
from train.core.mesh import each_device, replicated, split_along_batch


PROGRAMS = ("act", "finish", "reset", "learn", "keys")  # in the order they are lowered
CHOICES = ("auto", "on", "off")  # train.run --split-update
DEFAULT = "auto"


def wanted(choice: str, algo: str, devices: int | None = None) -> bool:
  """Whether `--split-update choice` splits a run's update here: PPO's, on one device (default:
  JAX's device count) of one process (auto: where JAX's backend is not the CPU). Not on several:
  on 2 CPU devices the programs' all-gather (the curriculum's normalizer) waited 40 s for the
  other device and XLA aborted the process (tests/test_runtime.py's run beside another worker,
  2026-11-29); on several GPUs it is not measured."""
  if choice not in CHOICES:
    raise ValueError(f"--split-update takes one of {', '.join(CHOICES)}, got {choice!r}")
  devices = jax.device_count() if devices is None else devices
  if algo != "ppo" or jax.process_count() > 1 or devices > 1:
    return False
  return choice == "on" or (choice == "auto" and jax.default_backend() != "cpu")


class SplitUpdate:
  """The programs of learner's update (PROGRAMS; with reset_apart=False four: `finish` and `reset`
  as one, `step`); `compile` makes of them an update(state) -> (state, metrics) equal to
  learner.update, up to float32 rounding."""

  def __init__(self, learner: PPO, core: TrackedRobotEnv, mesh, shardings, reset_apart: bool = True):
    self.learner, self.mesh, self.shardings = learner, mesh, shardings
    self.reset_apart = reset_apart  # the auto-reset a program of its own (False: split_update_speed.py's)
    self.names = PROGRAMS if reset_apart else ("act", "step", "learn", "keys")  # in the order they are lowered
    self.physics = each_device(jax.vmap(core.period), mesh)
    self.steps = learner.layout.unrolls * learner.layout.unroll_length  # env steps per update

  # --- the programs ----------------------------------------------------------------------
  def keys(self, key):
    """(SGD key, the policy's key at each env step, the next update's key): PPO.update's."""
    k_sgd, k_unroll, k_next = self.learner.keys(key)
    return k_sgd, self.learner.step_keys(k_unroll), k_next

  def act(self, env_state, policy_params, step_keys, i):
    """(actions, the policy's extras, the control period) at env step i."""
    actions, extras = self.learner.make_policy(policy_params)(env_state.obs, step_keys[i])
    return actions, extras, self.physics(env_state, actions)

  def finish(self, env_state, actions, period):
    """(the environments after the step, before new episodes start; the global state it updated;
    the observations it started from): the env's step_on, from the period."""
    nstate, glob = self.learner.env.step_on(env_state.replace(info={**env_state.info, PERIOD: period}), actions)
    return nstate.replace(info={k: v for k, v in nstate.info.items() if k != PERIOD}), glob, env_state.obs

  def reset(self, obs, actions, extras, nstate, glob):
    """(the environments after the step, new episodes started where theirs ended; the step's
    transition, as Brax's actor_step makes it: from observations obs, the step's actions and the
    policy's extras)."""
    after = _Stepped(self.learner.env.reset_where_done(nstate, glob))
    return acting.actor_step(after, nstate.replace(obs=obs), lambda *_: (actions, extras), None,
                             extra_fields=STATE_EXTRAS)

  def step(self, env_state, actions, extras, period):
    """finish, then reset: (the environments after the step, its transition)."""
    nstate, glob, obs = self.finish(env_state, actions, period)
    return self.reset(obs, actions, extras, nstate, glob)

  def learn(self, s: PPOState, transitions, k_sgd, k_next):
    """PPO.learn of the update's transitions (one per env step, in order)."""
    layout = self.learner.layout
    data = jax.tree_util.tree_map(lambda *x: jnp.stack(x), *transitions)  # [U * T, B, ...]
    data = jax.tree_util.tree_map(lambda x: x.reshape((layout.unrolls, layout.unroll_length) + x.shape[1:]), data)
    return self.learner.learn(s, batch_major(data), k_sgd, k_next)

  # --- compiling and running them --------------------------------------------------------
  def compile(self, shaped: PPOState, meanwhile: Callable[[], None] = lambda: None, stream=None,
              threads: int | None = None) -> Callable:
    """update(state) -> (state, metrics) for states like `shaped` (shapes, dtypes, shardings):
    lowers the programs and compiles each on its own thread as soon as it is lowered, the physics
    first; meanwhile() is called once all are lowered. On stream (if given): when each program was
    lowered and compiled, in seconds from the call. threads: compiling at once (default: all)."""
    t0, clock = time.time(), {}

    def compiled(name, lowered):
      clock[name] = [time.time() - t0]
      program = lowered.compile()
      clock[name].append(time.time() - t0)
      return program

    threads = threads or len(self.names)
    with concurrent.futures.ThreadPoolExecutor(threads, thread_name_prefix="compile-update") as pool:
      futures = {name: pool.submit(compiled, name, lowered) for name, lowered in self._lowered(shaped)}
      meanwhile()
      programs = {name: f.result() for name, f in futures.items()}
    if stream is not None:
      print("  its programs, lowered -> compiled (s): " + ", ".join(
          f"{name} {clock[name][0]:.1f} -> {clock[name][1]:.1f}" for name in self.names), file=stream, flush=True)
    steps = [jax.device_put(np.int32(i), replicated(self.mesh)) for i in range(self.steps)]  # on the device once
    # the ~0.56 M Python objects that building and compiling left (JAX's traces, MJX's model) out of
    # the collector's full passes: one pass over them took 0.27 s (scripts/analysis/gc_pause.py; 1 ms
    # once frozen), a pause in the host loop, which allocates many small objects each update
    gc.freeze()
    return functools.partial(self._run, programs, steps)

  def _run(self, programs: dict, steps: list, s: PPOState):
    k_sgd, step_keys, k_next = programs["keys"](s.key)
    env_state, policy_params, transitions = s.env_state, self.learner.policy_params(s), []
    for i in steps:
      actions, extras, period = programs["act"](env_state, policy_params, step_keys, i)
      if self.reset_apart:
        nstate, glob, obs = programs["finish"](env_state, actions, period)
        env_state, transition = programs["reset"](obs, actions, extras, nstate, glob)
      else:
        env_state, transition = programs["step"](env_state, actions, extras, period)
      transitions.append(transition)
    return programs["learn"](s.replace(env_state=env_state), tuple(transitions), k_sgd, k_next)

  def _lowered(self, shaped: PPOState):
    """(name, lowered program) of each program, act first: its physics takes the longest to compile.
    Every value with a batch axis (actions, periods, transitions) is split along it as the
    environments are (all their leaves have one); keys and the learner's state stay replicated."""
    rep, bat = replicated(self.mesh), split_along_batch(self.mesh)
    keys = jax.jit(self.keys, out_shardings=rep).trace(shaped.key)
    k_sgd, step_keys, k_next = _shaped(keys.out_info, rep)
    index = jax.ShapeDtypeStruct((), jnp.int32, sharding=rep)
    act = jax.jit(self.act, out_shardings=bat).trace(shaped.env_state, self.learner.policy_params(shaped), step_keys, index)
    yield "act", act.lower()
    actions, extras, period = _shaped(act.out_info, bat)
    if self.reset_apart:
      finish = jax.jit(self.finish, out_shardings=bat, donate_argnums=0).trace(shaped.env_state, actions, period)
      nstate, glob, obs = _shaped(finish.out_info, bat)
      last = jax.jit(self.reset, out_shardings=(self.shardings.env_state, bat), donate_argnums=3).trace(
          obs, actions, extras, nstate, glob)
      yield "finish", finish.lower()
    else:
      last = jax.jit(self.step, out_shardings=(self.shardings.env_state, bat), donate_argnums=0).trace(
          shaped.env_state, actions, extras, period)
    yield ("reset" if self.reset_apart else "step"), last.lower()
    transitions = (_shaped(last.out_info[1], bat),) * self.steps
    learn = jax.jit(self.learn, out_shardings=(self.shardings, rep), donate_argnums=0)
    yield "learn", learn.lower(shaped, transitions, k_sgd, k_next)
    yield "keys", keys.lower()


class _Stepped:
  """An env whose step returns a given state (acting.actor_step's env, the step made beforehand)."""

  def __init__(self, state):
    self.state = state

  def step(self, *_):
    return self.state


def _shaped(info, sharding):
  """The ShapeDtypeStructs of a traced program's out_info, every leaf with `sharding`."""
  return jax.tree_util.tree_map(lambda x: jax.ShapeDtypeStruct(x.shape, x.dtype, sharding=sharding), info)

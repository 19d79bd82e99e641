"""Programs compiled ahead of their first use: a run's in-training evaluations (Brax's evaluator,
the probe) trace in threads of their own once the training step is lowered, then compile while XLA
compiles the step and while the runs train.

XLA compiles without Python's lock and with threads of its own; tracing holds the lock. Three orders
were measured on one H200, the paper study's two programs (its SAC program of 40 one-robot runs, its
PPO program of 20 runs) started together under MPS, each from an empty cache:
- traced beside the step's own tracing: the SAC step compiled in 87-90 s instead of 39-42 s
  (results/speed/group/compile-order-H200-2026-11-29.json, results/speed/profile/solver-loop-H200-2026-11-29.json);
- started after the step had compiled and the runs' records were made: the SAC step compiled in 50 s,
  but SAC's training window with its first evaluation (~45 s into its training) held 21.5 s besides
  training, waiting for its program, and PPO's first probe waited ~46 s
  (results/speed/group/paper-packed-mps-1-H200-2026-11-29d.md);
- here, once the step is lowered: the SAC step compiled in 41 s, PPO's in 48 s; that SAC window held
  14.9 s, PPO's first probe waited ~16 s (results/speed/profile/compile-ahead-lowered-H200-2026-11-29.json).
The first evaluation then finds its program compiled: JAX's caches serve a call with the program
that `jit(f).lower(args).compile()` made for arguments of the same shapes, dtypes and placement. On
one H100 the PPO run's training step compiles in 30-42 s, Brax's evaluator in ~24 s and the probe
in ~16 s, one after the other (docs/benchmarks.md, "Compilation under XLA flags"). A program's
first evaluation and probe compiled at their first use cost its 40 SAC runs 46 s and 32 s on an
H200 (results/speed/group/paper-packed-2-H200-2026-11-28.md).

`auto` (train.run --compile-ahead) turns it on where JAX's backend is not the CPU. On a CPU the
compilers share the cores the run itself uses, and a short run may end before its first
evaluation, which would then have been compiled for nothing."""

from __future__ import annotations

import threading
from typing import Any, Callable

CHOICES = ("auto", "on", "off")  # train.run --compile-ahead
DEFAULT = "auto"


def wanted(choice: str) -> bool:
  """Whether `--compile-ahead choice` compiles ahead here (never in a run of several processes,
  jax.distributed, whose programs every process compiles in step)."""
  import jax  # noqa: PLC0415  (train.run reads CHOICES before JAX starts)
  if choice not in CHOICES:
    raise ValueError(f"--compile-ahead takes one of {', '.join(CHOICES)}, got {choice!r}")
  if jax.process_count() > 1:
    return False
  return choice == "on" or (choice == "auto" and jax.default_backend() != "cpu")


class CompiledAhead:
  """A computation whose programs may compile in a thread before its first use:
  `compile_ahead(example)` takes what it needs from `example` (a state like the ones it will be
  given) in the caller's thread, then compiles in a thread of its own; `ready()`, called before
  each use, waits for that thread. A failure there is dropped: the first use compiles again and
  raises where it is used."""

  _ahead: threading.Thread | None = None

  def ahead_job(self, example) -> Callable[[], Any]:
    """A call that compiles this computation's programs for states like `example` (the arguments
    made now, so that no state is read after the caller goes on, e.g. donates it)."""
    raise NotImplementedError

  def compile_ahead(self, example) -> None:
    job = self.ahead_job(example)
    self._ahead = threading.Thread(target=_quietly, args=(job,), name=f"compile-ahead-{type(self).__name__}",
                                   daemon=True)
    self._ahead.start()

  def ready(self) -> None:
    if self._ahead is not None:
      self._ahead.join()
      self._ahead = None


def _quietly(job: Callable[[], Any]) -> None:
  try:
    job()
  except Exception:  # noqa: BLE001  (the first use compiles again and raises there)
    pass


def start(choice: str, computations, example) -> None:
  """compile_ahead(example) for each computation that can (None and others are skipped), where
  `--compile-ahead choice` wants it here (wanted)."""
  if not wanted(choice):
    return
  for c in computations:
    if isinstance(c, CompiledAhead):
      c.compile_ahead(example)


def settle(computations) -> None:
  """Waits for the compilations ahead still running (a run that ended before its first evaluation):
  a thread left inside XLA's compiler when the interpreter exits can abort the process."""
  for c in computations:
    if isinstance(c, CompiledAhead):
      c.ready()


def brax_evaluation_job(evaluator, params) -> Callable[[], Any]:
  """A call that compiles the unroll of Brax's `acting.Evaluator` for params like these, with the
  arguments its `run_evaluation` gives it next: the episodes' state it donates, the params and the
  key it splits off. Those are private attributes (brax 0.14: `_generate_eval_unroll`,
  `_eval_state_to_donate`, `_key`), read here only; tests/test_compile_ahead.py fails where an
  upgrade changes them."""
  import jax  # noqa: PLC0415
  unroll, episodes = evaluator._generate_eval_unroll, evaluator._eval_state_to_donate  # noqa: SLF001
  unroll_key = jax.random.split(evaluator._key)[1]  # noqa: SLF001  (as run_evaluation splits it)
  return lambda: unroll.lower(episodes, params, unroll_key).compile()

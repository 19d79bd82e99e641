"""Small things several test files share."""

import json
import os

# a small task variant for training tests (compiles and runs quickly on a CPU): no beams, short
# episodes of 0.02 s control steps (2 physics steps each, not 25: the training runs' time on the CPU
# is mostly physics; 0.05 s until 2026-11-29 ran them 2.5x slower), the default contact culling (24
# slots: until 2026-11-27 every contact was kept, for fear that culling's top_k would part the 2-device
# run from the 1-device one in tests/test_runtime.py; it did not in the runs tried, 2026-11-27, and the
# runs are cheaper to step); two steps observed, so that training, export, ONNX and SB3 tests run a
# stacked observation (tests/test_observation_history.py)
TINY_SETTINGS = ("observation.parts=[v, flippers_paired, arm, pitch]", "episode.max_steps=8", "control.period=0.02",
                 "observation.history=2")
TINY = [arg for setting in TINY_SETTINGS for arg in ("--set", setting)]


def run_id(out: str) -> str:
  """The run id recorded in a run directory."""
  with open(os.path.join(out, "run.json")) as f:
    return json.load(f)["run_id"]

# the SAC program of two tasks (direction, sampler and reward kind all differ) of test_task_pack and
# test_evaluator, and the single run (its first) of test_compile_ahead
PACK = (("asc-inc-cog", 0), ("des-uni-ang", 1))  # (task, seed) of each run


def pack_plans(out) -> list:
  """The PACK's run plans (tiny SAC on the CPU, runs under out/), with Brax's evaluator: 2
  evaluations of 4 episodes."""
  import dataclasses  # noqa: PLC0415
  from train.core.plan import plan_run  # noqa: PLC0415
  from train.run import parser  # noqa: PLC0415
  plans = [plan_run(parser().parse_args(["--task", task, "--seed", str(seed), "--algo", "sac", "--preset", "cpu", *TINY,
                                         "--out", os.path.join(str(out), task)])) for task, seed in PACK]
  return [dataclasses.replace(p, preset=dataclasses.replace(p.preset, num_evals=2, num_eval_envs=4)) for p in plans]


# the `train.run --seeds` program of test_evaluator and test_compile_ahead: the PACK's first run (its
# task) with these seeds, so that the two files' evaluation and probe programs are the same
SEEDS = [0, 3]


def seeds_states(t):
  """The fresh learner states of run t's task with each of SEEDS (a batch axis: the program's runs)."""
  import jax  # noqa: PLC0415
  import jax.numpy as jnp  # noqa: PLC0415
  return jax.jit(jax.vmap(t.learner.init))(jnp.stack([jax.random.PRNGKey(s) for s in SEEDS]))


class Compilations:
  """While open, in the main thread: the seconds of each XLA compilation and the number of programs
  loaded from the persistent compilation cache instead (JAX's monitoring events)."""

  def __enter__(self):
    import threading  # noqa: PLC0415
    import jax  # noqa: PLC0415
    self.seconds, self.cache_hits, self._on = [], 0, True

    def main() -> bool:
      return threading.current_thread() is threading.main_thread()

    def compiled(event: str, seconds: float, **_):
      if self._on and event == "/jax/core/compile/backend_compile_duration" and main():
        self.seconds.append(seconds)

    def loaded(event: str, **_):
      if self._on and event == "/jax/compilation_cache/cache_hits" and main():
        self.cache_hits += 1
    jax.monitoring.register_event_duration_secs_listener(compiled)
    jax.monitoring.register_event_listener(loaded)
    return self

  def __exit__(self, *exc):
    self._on = False

  def large(self) -> int:
    """Programs compiled (over 0.5 s) or loaded from the cache (only those that took over 1 s to
    compile are stored there: not the eager operations around an evaluation)."""
    return sum(s > 0.5 for s in self.seconds) + self.cache_hits


HELD_OUT = "middle"  # the ppo_run fixture's one held-out staircase (conftest.py)
HELD_OUT_SET = f"evaluation.held_out=[{{name: {HELD_OUT}, tread: 0.43, riser: 0.17, steps: 4}}]"  # its --set
TRAIN_TINY = ["--task", "asc-inc-cog", "--preset", "cpu", *TINY]  # the ppo_run fixture's run, less its length


def start_training(args: list[str], log_path: str, env: dict | None = None):
  """`python -m train.run ARGS` in a subprocess on the CPU, its output in log_path."""
  import subprocess  # noqa: PLC0415
  import sys  # noqa: PLC0415
  root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
  log = open(log_path, "w")
  return subprocess.Popen([sys.executable, "-m", "train.run", *args], cwd=root, stdout=log,
                          stderr=subprocess.STDOUT, env={**os.environ, "JAX_PLATFORMS": "cpu", **(env or {})})


def wait_for(predicate, proc, timeout_s: float, what: str) -> None:
  """Polls predicate() every 20 ms; fails if the process ends first or time runs out."""
  import time  # noqa: PLC0415
  t_end = time.time() + timeout_s
  while not predicate():
    assert proc.poll() is None, f"the run ended (rc {proc.returncode}) before {what}"
    assert time.time() < t_end, f"no {what} within {timeout_s} s"
    time.sleep(0.02)


def checkpoint_steps(out: str) -> list[int]:
  path = os.path.join(out, "checkpoints")
  return sorted(int(d) for d in os.listdir(path) if d.isdigit()) if os.path.isdir(path) else []


CHROMIUM_MISSING = "the browser tests need the system Chromium (apt-get install chromium), or MJX_TRACKS_NO_BROWSER=1"


def chromium() -> str:
  """The system Chromium's path (the browser tests fail without it; MJX_TRACKS_NO_BROWSER=1 skips them)."""
  import shutil  # noqa: PLC0415
  path = shutil.which("chromium") or shutil.which("chromium-browser")
  assert path, CHROMIUM_MISSING
  return path


def await_runs_on_stdin(mp, folders: list[str]) -> list[bool]:
  """For `train.evaluate ... --await-runs` called in this process: sys.stdin names the folders (and
  --await-runs's setting of the GPU's memory is undone with `mp`, a pytest MonkeyPatch); returns
  the list each trace of an evaluation rollout appends to: whether stdin had been read by then."""
  import io  # noqa: PLC0415
  from train import evaluation  # noqa: PLC0415
  stdin, traced, original = io.StringIO("".join(f"{f}\n" for f in folders)), [], evaluation.trial_rollout

  def recording(*args, **kwargs):
    core, rollout = original(*args, **kwargs)
    return core, lambda *a, **k: (traced.append(stdin.tell() > 0), rollout(*a, **k))[1]
  mp.setattr(evaluation, "trial_rollout", recording)
  mp.setattr("sys.stdin", stdin)
  mp.setenv("XLA_PYTHON_CLIENT_PREALLOCATE", "false")
  return traced

"""Issue 30, compilation and launches: how long the training step of `python -m train.run` compiles from
an empty cache under XLA flag variants, and how fast each trains. Each variant runs
`python -m train.run --task TASK --algo ALGO [--preset P] --steps STEPS --early-stop none --seed 0 --hp H ...`
(H: --hp, default training_metrics_steps=81920, a PPO [train] line every update) in its own process with
its own empty compilation cache (MJX_TRACKS_CACHE) and MJX_TRACKS_COMPILE_LOG, then
`python -m train.evaluate RUN --scene hardest --trials 100` (its wall time: the evaluation
program's compilation and 100 trials). Writes OUT/compile-flags.json: per variant the seconds its
training step took to compile and its steady training steps/s (the median of its training reports
after the first), both read from the run's database (train.bench.runs), the ten longest XLA
compilations of its compilation log, the evaluation's wall s; with the device, command and date.
Usage (GPU host): python scripts/gpu/compile_flags.py OUT [--task asc-inc-cog] [--steps 600000]
    [--algo ppo] [--preset P] [--hp KEY=VALUE ...] [--variants NAME,...] [--skip-eval] [--train-args '...']
E.g. the paper's one-robot SAC, launch-bound (~16 ms a training step): --algo sac --preset paper --steps 5000
--hp num_evals=1 --hp max_replay_size=20000 --hp training_metrics_steps=500 --skip-eval.
--code DIR runs both commands from another checkout (e.g. an earlier commit's `git archive` unpacked):
a before / after pair in one device call, each its own invocation (OUT/before, OUT/after)."""

from __future__ import annotations

import argparse
import datetime
import json
import os
import shlex
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
from mjx_tracks.compile_cache import longest_compilations  # noqa: E402
from train.bench import runs  # noqa: E402

VARIANTS = {  # name -> XLA_FLAGS added to the environment's
    "default": "",
    "autotune-0": "--xla_gpu_autotune_level=0",
    "no-triton-gemm": "--xla_gpu_enable_triton_gemm=false",
    "autotune-0-no-triton-gemm": "--xla_gpu_autotune_level=0 --xla_gpu_enable_triton_gemm=false",
    # XLA's compilation on 16 threads (jaxlib 0.11 refuses --xla_gpu_enable_llvm_module_compilation_parallelism)
    "force-16": "--xla_gpu_force_compilation_parallelism=16",
    "autotune-0-force-16": "--xla_gpu_autotune_level=0 --xla_gpu_force_compilation_parallelism=16",
    # cheaper code generation on 16 threads: LLVM without its expensive passes; LLVM at -O1; ptxas without optimization
    "cheap-llvm-force-16": "--xla_llvm_disable_expensive_passes=true --xla_gpu_force_compilation_parallelism=16",
    "llvm-o1-force-16": "--xla_backend_optimization_level=1 --xla_gpu_force_compilation_parallelism=16",
    "ptxas-o0-force-16": "--xla_gpu_disable_gpuasm_optimizations=true --xla_gpu_force_compilation_parallelism=16",
    # CUDA graphs: XLA's command buffers also over while loops and conditionals (a lax.scan of training steps
    # or of physics substeps becomes one graph launch instead of a launch per kernel), and none at all
    "cmdbuf-while": "--xla_gpu_enable_command_buffer=FUSION,CUBLAS,CUBLASLT,CUSTOM_CALL,CUDNN,CONDITIONAL,WHILE",
    "cmdbuf-off": "--xla_gpu_enable_command_buffer=",
    # XLA's autotuning results written to a file by one process and read by the next (its own empty
    # compilation cache, so JAX's per-fusion autotune cache inside it is empty too): what the compilation
    # costs where autotuning results come with the program, the training speed kept. Run in this order.
    "autotune-dump": "--xla_gpu_dump_autotune_results_to={work}/autotune-results.txt",
    "autotune-load": "--xla_gpu_load_autotune_results_from={work}/autotune-results.txt",
}


COMPILE_LINES = ("compiled in", "  its programs")  # train.core.build.compile_update's report


def _variant(name: str, flags: str, args, work: str) -> dict:
  flags = flags.format(work=work)
  env = {**os.environ, "MJX_TRACKS_CACHE": f"{work}/{name}-cache", "MJX_TRACKS_COMPILE_LOG": f"{work}/{name}.compile.log",
         "XLA_FLAGS": " ".join(x for x in (os.environ.get("XLA_FLAGS", ""), flags) if x)}
  run, database = f"{work}/{name}-run", f"{work}/{name}.sqlite"
  cmd = [sys.executable, "-m", "train.run", "--task", args.task, "--algo", args.algo, "--steps", str(args.steps),
         "--early-stop", "none", "--seed", "0", "--out", run, "--db", database,
         *(["--preset", args.preset] if args.preset else []), *(x for h in args.hp for x in ("--hp", h)),
         *shlex.split(args.train_args)]
  t0 = time.time()
  proc = subprocess.run(cmd, env=env, capture_output=True, text=True, cwd=args.code)
  out = proc.stdout + (f"\n[stderr] {proc.stderr[-400:]}" if proc.returncode else "")  # why a variant failed
  wall = time.time() - t0
  made = os.path.isfile(database)  # not where the run failed before it started its records
  if args.skip_eval:
    ev, eval_wall, success = None, None, None
  else:
    ev, eval_wall, success = _evaluate(run, env, work, name, args.code)
  return {"xla_flags": flags, "compile_s": runs.compile_seconds(database) if made else None,
          "train_steps_per_s": runs.steady_rate(runs.training_rates(database)) if made else None,
          "run_wall_s": round(wall, 1),
          "eval_wall_s": eval_wall, "eval_rc": None if ev is None else ev.returncode, "hardest_success": success,
          "longest_compilations": longest_compilations(env["MJX_TRACKS_COMPILE_LOG"]),
          "compile_lines": [line.strip() for line in proc.stdout.splitlines() if line.startswith(COMPILE_LINES)],
          "log_tail": out[-600:]}


def _evaluate(run: str, env: dict, work: str, name: str, code: str | None):
  """(the process, its wall s, hardest-staircase success or None) of evaluating the variant's run."""
  t0 = time.time()
  ev = subprocess.run([sys.executable, "-m", "train.evaluate", run, "--scene", "hardest", "--trials", "100",
                       "--out", f"{work}/{name}-eval.json"], env=env, capture_output=True, text=True, cwd=code)
  eval_wall = round(time.time() - t0, 1)
  success = json.load(open(f"{work}/{name}-eval.json"))["metrics"]["success"]["mean"] if ev.returncode == 0 else None
  return ev, eval_wall, success


def main() -> None:
  p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
  p.add_argument("out")
  p.add_argument("--task", default="asc-inc-cog")
  p.add_argument("--steps", type=int, default=600_000)
  p.add_argument("--algo", default="ppo")
  p.add_argument("--preset", default=None, help="train.run's --preset (default: its own)")
  p.add_argument("--hp", action="append", default=None,
                 help="train.run's --hp KEY=VALUE, repeatable (default: training_metrics_steps=81920)")
  p.add_argument("--variants", default=",".join(VARIANTS), help="comma-separated, of " + ", ".join(VARIANTS))
  p.add_argument("--train-args", default="", help="more train.run arguments for every variant, one string "
                 "(e.g. '--compile-ahead off')")
  p.add_argument("--skip-eval", action="store_true", help="no evaluation after each run (compile and training only)")
  p.add_argument("--code", default=None, metavar="DIR", help="run train.run and train.evaluate from this checkout "
                 "(its code: `python -m` finds it first), not this one's")
  args = p.parse_args()
  if args.code and not os.path.isfile(os.path.join(args.code, "train", "run.py")):
    p.error(f"--code {args.code}: no train/run.py there (python -m would run this checkout's code instead)")
  args.hp = args.hp or ["training_metrics_steps=81920"]  # a [train] line (steps/s) every PPO update
  import jax  # noqa: PLC0415
  device = f"{jax.devices()[0].device_kind} x {jax.device_count()}, JAX {jax.__version__}"
  results = {}
  with tempfile.TemporaryDirectory() as work:
    for name in args.variants.split(","):
      results[name] = _variant(name, VARIANTS[name], args, work)
      print(name, {k: v for k, v in results[name].items() if k not in ("log_tail", "longest_compilations")}, flush=True)
      os.makedirs(args.out, exist_ok=True)
      json.dump({"device": device, "command": "python scripts/gpu/compile_flags.py " + shlex.join(sys.argv[1:]),
                 "code": args.code or "this checkout",
                 "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
                 "variants": results}, open(f"{args.out}/compile-flags.json", "w"), indent=1)


if __name__ == "__main__":
  main()

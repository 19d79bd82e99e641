"""group: the wall time of N runs trained as one program (`train.run --seeds 0,...,N-1`) against
runs trained one process each, one after another (the first `--singles` seeds), every process
timed from start to exit. Issue 30's target is N = 20 one-robot SAC runs of the paper's regime in
the wall time of 2 single runs: `group_in_singles` (the program's wall time over one single run's
mean) <= 2. Each process compiles from scratch in an empty compilation cache of its own (`--warm`:
the machine's cache, e.g. for a quick check); every run trains its whole budget (`--early-stop
none`); extra `train.run` arguments follow `--`. With `--tasks T,T,...` (runs of several tasks in
one program: `train.run --tasks`), a third process trains the same number of runs spread over
those tasks (N / tasks seeds each) after the program of N seeds of the first task:
`tasks_in_seeds` (its wall time over the seeds program's) is what holding several tasks costs."""

from __future__ import annotations

import os
import statistics
import sys
import tempfile

from train.bench.result import BenchInputError
from train.bench.timing import process_wall_s

PAPER = ["--task", "asc-inc-cog", "--algo", "sac", "--preset", "paper"]  # the default runs: the paper's regime
TRAIN = ("-m", "train.run")  # what each timed process runs, after this Python


def add_args(p) -> None:
  p.add_argument("--runs", type=int, default=20, help="runs in the program (seeds 0..N-1; default %(default)s)")
  p.add_argument("--singles", type=int, default=2, help="runs timed one process each (default %(default)s)")
  p.add_argument("--steps", type=int, default=20_000, help="steps of every run (default: the paper's %(default)s)")
  p.add_argument("--tasks", metavar="T,T,...", help="also time the runs spread over these tasks in one program "
                                                     "(the first task: the singles' and the seeds program's; its "
                                                     "--task in ARGS is replaced)")
  p.add_argument("--warm", action="store_true", help="use the machine's compilation cache (default: empty caches)")
  p.add_argument("--work", help="folder for the runs (default: a new temporary one)")
  p.add_argument("train_args", nargs="*", metavar="-- ARGS",
                 help=f"train.run arguments of every run (default: {' '.join(PAPER)})")


def _timed(argv: list[str], work: str, name: str, warm: bool) -> float:
  """Runs `python -m train.run ARGV --out WORK/NAME --db WORK/NAME.sqlite`; its process wall time (s)."""
  cmd = [sys.executable, *TRAIN, *argv, "--out", os.path.join(work, name),
         "--db", os.path.join(work, f"{name}.sqlite")]
  log = os.path.join(work, f"{name}.log")
  rc, wall = process_wall_s(cmd, None if warm else os.path.join(work, f"{name}-cache"), log)
  if rc != 0:
    raise BenchInputError(f"{' '.join(cmd[1:])} exited {rc}; its output: {log}")
  return wall


def train_args(args) -> list[str]:
  """The train.run arguments every timed run shares (each adds --seed or --seeds, --out, --db)."""
  return [*(args.train_args or PAPER), "--steps", str(args.steps), "--early-stop", "none"]


def _tasks(args) -> list[str]:
  tasks = [x.strip() for x in args.tasks.split(",")] if args.tasks else []
  if tasks and (len(set(tasks)) != len(tasks) or len(tasks) < 2 or args.runs % len(tasks)):
    raise BenchInputError(f"--tasks: two or more different tasks that divide --runs {args.runs}; got {args.tasks!r}")
  return tasks


def _without_task(argv: list[str]) -> list[str]:
  """argv less its --task NAME."""
  i = argv.index("--task") if "--task" in argv else None
  return argv if i is None else [*argv[:i], *argv[i + 2:]]


def run(args) -> tuple[list[dict], dict]:
  tasks = _tasks(args)
  if args.runs < 2 or not (0 if tasks else 1) <= args.singles <= args.runs:
    raise BenchInputError(f"--runs >= 2 and 1 <= --singles <= --runs (0 with --tasks); got {args.runs} and {args.singles}")
  work = args.work or tempfile.mkdtemp(prefix="bench-group-")
  os.makedirs(work, exist_ok=True)  # a --work folder that does not exist yet
  base = train_args(args)
  if tasks:  # the singles and the seeds program: the first task's
    base = ["--task", tasks[0], *_without_task(base)]
  rows = []
  for seed in range(args.singles):
    rows.append({"mode": "single", "seed": seed, "process_wall_s": round(_timed([*base, "--seed", str(seed)], work,
                                                                                 f"single-s{seed}", args.warm), 1)})
    print(rows[-1], flush=True)
  seeds = ",".join(map(str, range(args.runs)))
  rows.append({"mode": "group", "runs": args.runs,
               "process_wall_s": round(_timed([*base, "--seeds", seeds], work, "group", args.warm), 1)})
  print(rows[-1], flush=True)
  group = rows[-1]["process_wall_s"]
  summary = {"train_args": base, "runs": args.runs, "work": work}
  if tasks:
    seeds = ",".join(map(str, range(args.runs // len(tasks))))
    spread = ["--tasks", ",".join(tasks), *_without_task(base), "--seeds", seeds]
    rows.append({"mode": "tasks", "runs": args.runs, "tasks": tasks,
                 "process_wall_s": round(_timed(spread, work, "tasks", args.warm), 1)})
    print(rows[-1], flush=True)
    summary["tasks_in_seeds"] = round(rows[-1]["process_wall_s"] / group, 2)
  if args.singles:
    single = statistics.mean(r["process_wall_s"] for r in rows if r["mode"] == "single")
    summary.update(single_mean_s=round(single, 1), group_in_singles=round(group / single, 2),
                   group_speedup=round(args.runs * single / group, 2))
  return rows, summary

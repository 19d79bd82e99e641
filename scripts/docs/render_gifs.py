"""Renders one GIF per task of a study (or of a folder of run folders): trial 0 of its first finished
run's policy on the task's hardest configuration (uniform scenes for navigation), until the episode
ends, with the trial's outcome in OUT/index.json. Runs the tasks in parallel processes (EGL on a GPU
host).

python scripts/docs/render_gifs.py STUDY_OR_RUNS_FOLDER OUT [--tasks T ...] [--jobs 8]
"""

from __future__ import annotations

import argparse
import concurrent.futures
import datetime
import json
import os
import subprocess
import sys

from mjx_tracks.envs.config import TaskConfig
from train.core.run_record import run_config
from train.study.executor import cell_folder_of, read_cells


def _finished(source: str) -> list[str]:
  """Run folders of a study's finished cells (by cell id), or the run folders inside a folder."""
  if not os.path.exists(os.path.join(source, "state.json")):
    return sorted(os.path.join(source, d) for d in os.listdir(source) if os.path.exists(os.path.join(source, d, "run.json")))
  return [cell_folder_of(source, cid) for cid, cell in sorted(read_cells(source).items()) if cell["status"] == "done"]


def first_runs(source: str, tasks: list[str] | None) -> dict[str, tuple[str, TaskConfig]]:
  """task -> the folder and config of its first finished run that has an exported policy."""
  out: dict[str, tuple[str, TaskConfig]] = {}
  for run in _finished(source):
    if not os.path.isdir(os.path.join(run, "policy")):
      continue
    cfg = run_config(run)
    if (not tasks or cfg.task in tasks) and cfg.task not in out:
      out[cfg.task] = (run, cfg)
  return out


def render(task: str, run: str, cfg: TaskConfig, out: str) -> dict:
  """One GIF (OUT/<task>.gif) through train.evaluate --video: trial 0 on the task's hardest
  configuration, or uniform scenes (navigation); the trial's figures beside it."""
  scene, report = "hardest" if cfg.scene.has_hardest else "uniform", os.path.join(out, f"{task}.json")
  cmd = [sys.executable, "-m", "train.evaluate", run, "--scene", scene, "--trials", "1", "--out", report,
         "--db", os.path.join(out, "gifs.sqlite"), "--video", os.path.join(out, f"{task}.gif")]
  env = {**os.environ, "XLA_PYTHON_CLIENT_PREALLOCATE": "false"}  # beside training runs on the same GPUs
  res = subprocess.run(cmd, capture_output=True, text=True, env=env)
  if res.returncode != 0:
    return {"task": task, "error": res.stderr[-2000:]}
  m = json.load(open(report))["metrics"]
  return {"task": task, "run": os.path.basename(run), "scene": scene, "success": m["success"]["mean"],
          "progress": m["progress"]["mean"], "tipped_over": m["tipped_over"]["mean"], "steps": m["length"]["mean"]}


def main(argv: list[str] | None = None) -> int:
  p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
  p.add_argument("source", help="a study folder, or a folder of run folders")
  p.add_argument("out")
  p.add_argument("--tasks", nargs="*")
  p.add_argument("--jobs", type=int, default=8)
  args = p.parse_args(argv)
  os.makedirs(args.out, exist_ok=True)
  runs = first_runs(args.source, args.tasks)
  with concurrent.futures.ThreadPoolExecutor(args.jobs) as pool:
    done = list(pool.map(lambda t: render(t, *runs[t], args.out), sorted(runs)))
  for d in done:
    print(json.dumps(d)[:300], flush=True)
  index = {"command": "python scripts/docs/render_gifs.py " + " ".join(sys.argv[1:] if argv is None else argv),
           "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"), "gifs": done}
  json.dump(index, open(os.path.join(args.out, "index.json"), "w"), indent=1)
  return 1 if any("error" in d for d in done) or not done else 0


if __name__ == "__main__":
  sys.exit(main())

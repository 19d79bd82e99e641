"""A stand-in for `train.run` / `train.evaluate` in study tests (no JAX): `train ARGS` makes a run
folder with a checkpoint every 100 steps (0.1 s each), `evaluate RUN` writes eval-hardest.json.
FAKE_CRASH_SEED: that seed's first session exits 1 after its first checkpoint; FAKE_SLOW_SEED:
that seed sleeps 1 s per checkpoint (time to kill its worker)."""

import argparse
import json
import os
import sys
import time


def train(argv: list[str]) -> int:
  p = argparse.ArgumentParser()
  for name in ("--task", "--algo", "--preset", "--steps", "--seed", "--out", "--db", "--resume", "--early-stop"):
    p.add_argument(name)
  p.add_argument("--set", action="append", default=[])
  a = p.parse_args(argv)
  out = a.resume or a.out
  meta_path = os.path.join(out, "run.json")
  if a.resume:
    meta = json.load(open(meta_path))
  else:
    meta = {"task": a.task, "seed": int(a.seed), "steps": int(a.steps), "sessions": 0}
  meta["sessions"] += 1
  os.makedirs(os.path.join(out, "checkpoints"), exist_ok=True)
  done = [int(d) for d in os.listdir(os.path.join(out, "checkpoints"))]
  step = max(done, default=0)
  json.dump(meta, open(meta_path, "w"))
  while step < meta["steps"]:
    time.sleep(1.0 if str(meta["seed"]) == os.environ.get("FAKE_SLOW_SEED") else 0.1)
    step += 100
    os.makedirs(os.path.join(out, "checkpoints", str(step)))
    if str(meta["seed"]) == os.environ.get("FAKE_CRASH_SEED") and meta["sessions"] == 1:
      return 1
  return 0


def evaluate(argv: list[str]) -> int:
  out = argv[0]
  json.dump({"metrics": {"success": {"mean": 1.0}}}, open(os.path.join(out, "eval-hardest.json"), "w"))
  return 0


if __name__ == "__main__":
  sys.exit(train(sys.argv[2:]) if sys.argv[1] == "train" else evaluate(sys.argv[2:]))

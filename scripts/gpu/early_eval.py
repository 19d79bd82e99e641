"""`python scripts/gpu/early_eval.py OUT_JSON [STEPS]`: on a GPU host, the paper study's SAC pack (its
40 one-robot runs, scripts/gpu/pack_args.py's program) trained for STEPS steps (default 4,000; three
in-training evaluations) and evaluated on the study's suite (100 trials a scene), as a study's worker
runs it (train.study.worker.run_pack), twice: first with the evaluation started after the training
(early=False, as before 2026-11-29), then beside it (early=True: `train.evaluate --await-runs`,
train.eval_ahead). Each variant has a compilation cache of its own, empty at its start. Writes the
seconds of each phase (the training process, then from its end to the evaluation's) and the
evaluation's own timing lines to OUT_JSON. The first checkpoints, which the early evaluation waits for,
come ~60 s into the training (CHECKPOINT_EVERY_S): at fewer steps it would have no time to compile."""

import json
import os
import re
import shutil
import subprocess
import sys
import time

from pack_args import study_pack  # scripts/gpu/pack_args.py, beside this script
from train.study import worker
from train.study.spec import pack_folders, pack_train_args


def sac_pack():
  """(train.run arguments, run folders, train.evaluate arguments) of the paper study's SAC pack."""
  spec, pack = study_pack("sac")
  return pack_train_args(pack), pack_folders(pack), pack[0].eval_args(spec.eval_trials)


def timed_pack(early: bool, steps: int, root: str) -> dict:
  """run_pack of the SAC pack with its evaluation early or not; the phases' seconds."""
  train_args, members, eval_args = sac_pack()
  marks, call, together, finish = {}, worker._call, worker._evaluate_together, worker.EarlyEvaluation.finish

  def timed(name, fn, only=lambda a, k: True):
    def wrapper(*a, **k):
      out = fn(*a, **k)
      if only(a, k):
        marks[name] = time.monotonic()
      return out
    return wrapper
  # _call(argv, log, pid_path, phase) runs the training, and the evaluation after it (early=False)
  worker._call = timed("trained", call, lambda a, k: (a[3] if len(a) > 3 else k.get("phase")) == "train")
  worker._evaluate_together = timed("evaluated", together)
  worker.EarlyEvaluation.finish = timed("evaluated", finish)
  os.environ["MJX_TRACKS_CACHE"] = os.path.join(root, f"cache-{early}")
  handoff, _lock = worker.Handoff.create(os.path.join(root, f"study-{early}"))
  args = [*train_args, "--steps", str(steps), "--hp", "num_evals=3"]
  t0 = time.monotonic()
  try:
    res = worker.run_pack(args, members, eval_args, handoff=handoff, early=early)
  finally:
    worker._call, worker._evaluate_together, worker.EarlyEvaluation.finish = call, together, finish
  first = res["cells"][members[0]]
  log = open(os.path.join(first["moved"], "study-attempts.log")).read() if first.get("moved") else ""
  timing = [line for line in log.splitlines() if re.search(r" in [\d.]+ s(\)| \()", line) and "[" not in line]
  return {"early": early, "rc": sorted({c["rc"] for c in res["cells"].values()}),
          "phases": sorted({c["phase"] for c in res["cells"].values()}),
          "training_process_s": round(marks["trained"] - t0, 1),
          "after_training_s": round(marks["evaluated"] - marks["trained"], 1) if "evaluated" in marks else None,
          "pack_s": round(time.monotonic() - t0, 1), "evaluation_lines": timing}


def main(argv: list[str]) -> int:
  out, steps = argv[0], int(argv[1]) if len(argv) > 1 else 4000
  root = "/tmp/early-eval"
  shutil.rmtree(root, ignore_errors=True)  # a warm machine keeps /tmp: empty caches
  os.makedirs(root)
  pack_args, _, eval_args = sac_pack()
  result = {"command": f"python scripts/gpu/early_eval.py OUT_JSON {steps}",
            "device": subprocess.run(["nvidia-smi", "--query-gpu=name", "--format=csv,noheader"],
                                     capture_output=True, text=True).stdout.strip(),
            "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()), "pack_args": pack_args,
            "eval_args": eval_args, "variants": []}
  for early in (False, True):
    result["variants"].append(timed_pack(early, steps, root))
    print(json.dumps(result["variants"][-1]), flush=True)
    with open(out, "w") as f:
      json.dump(result, f, indent=1)
  return 0


if __name__ == "__main__":
  sys.exit(main(sys.argv[1:]))

#!/usr/bin/env bash
# On a GPU host: the paper study's two programs (the packs `python -m train.study paper-packed --plan`
# prints: the SAC program of 40 one-robot runs, the PPO program of 20 runs x 4,096 robots; their
# commands come from configs/studies/paper-packed.yaml through train.study.spec.pack_train_args) side
# by side on one GPU under a CUDA MPS daemon of this script's own, once per VARIANT, each for EACH
# seconds (default 270, compilation included: ~90 s from an empty cache, less from the shared one in
# /tmp/mps-pair-cache). A VARIANT is SHARE:PRIORITY for the PPO program: its
# CUDA_MPS_ACTIVE_THREAD_PERCENTAGE (train.study's: train.study.mps.SM_SHARE, 85) and its
# CUDA_MPS_CLIENT_PRIORITY (0 normal, 1 below normal: NVIDIA's MPS manual); the SAC program runs at
# SM_SHARE and priority 0, as train.study starts it. Writes $OUT/mps-pair.json: each variant's
# programs' training-step compile seconds (the first variant's from an empty cache, the next ones' mostly
# loaded from the shared one) and training steps/s per run at each report (the median over its runs'
# training rows), read from each program's database by train.bench.runs, and prints them. Figures
# are comparable within one call (one machine); alone: PPO 6,230, SAC ~37 (2026-11-28).
# Measured: results/speed/group/mps-pair-priority-H200-2026-11-28.json (docs/benchmarks.md).
# STAGGER=1 starts the PPO program once the SAC program has compiled its training step ("compiled
# in"), not beside it; COLD=1 gives each variant an empty compilation cache of its own. Each
# program's ready_s: from the variant's start to its training step's compiled event (its training's
# start; the database's times are whole seconds).
# Usage: EACH=270 bash scripts/gpu/mps_pair.sh 85:0 85:1
set -uo pipefail
export PYTHONUNBUFFERED=1 MJX_TRACKS_CACHE=/tmp/mps-pair-cache XLA_PYTHON_CLIENT_MEM_FRACTION=0.45
work=/tmp/mps-pair
for variant in "$@"; do
  [[ $variant =~ ^[0-9]+:[01]$ ]] \
    || { echo "error: a variant is SHARE:PRIORITY (e.g. 85:1), got '$variant'" >&2; exit 2; }
done
[ $# -gt 0 ] || { echo "usage: EACH=270 bash scripts/gpu/mps_pair.sh SHARE:PRIORITY ..." >&2; exit 2; }
# train.study's share of the SMs, then the study's two packs' train.run arguments (scripts/gpu/pack_args.py)
study_share=$(python3 -c 'from train.study.mps import SM_SHARE; print(SM_SHARE)') || exit 1
sac_args=$(python3 scripts/gpu/pack_args.py sac) && ppo_args=$(python3 scripts/gpu/pack_args.py ppo) \
  || { echo "error: the study has no SAC and PPO packs" >&2; exit 1; }
read -ra sac <<< "$sac_args"
read -ra ppo <<< "$ppo_args"
for variant in "$@"; do
  share=${variant%%:*} priority=${variant#*:}
  dir=$work/$share-$priority && rm -rf "$dir" && mkdir -p "$dir/pipe" "$dir/log"
  [ "${COLD:-0}" = 1 ] && export MJX_TRACKS_CACHE=$dir/cache
  date +%s > "$dir/t0"
  export CUDA_MPS_PIPE_DIRECTORY=$dir/pipe CUDA_MPS_LOG_DIRECTORY=$dir/log
  nvidia-cuda-mps-control -d || { echo "error: no MPS daemon for $variant" >&2; exit 1; }
  for prog in sac ppo; do
    if [ $prog = sac ]; then args=("${sac[@]}") sm=$study_share prio=0
    else args=("${ppo[@]}") sm=$share prio=$priority; fi
    CUDA_MPS_ACTIVE_THREAD_PERCENTAGE=$sm CUDA_MPS_CLIENT_PRIORITY=$prio timeout "${EACH:-270}" \
      python3 -m train.run "${args[@]}" --out "$dir/$prog" --db "$dir/$prog.sqlite" > "$dir/$prog.log" 2>&1 &
    if [ $prog = sac ] && [ "${STAGGER:-0}" = 1 ]; then
      until grep -q "compiled in" "$dir/sac.log" 2>/dev/null || ! kill -0 $! 2>/dev/null; do sleep 1; done
    fi
  done
  wait
  echo quit | nvidia-cuda-mps-control
done
python3 - "$work" "$@" <<'PY'
import json, os, sys
from train.bench.runs import compile_seconds, compiled_at, training_rates
work, variants, found = sys.argv[1], sys.argv[2:], {}
for v in variants:
  for prog in ("sac", "ppo"):
    path = os.path.join(work, v.replace(":", "-"), f"{prog}.sqlite")
    made = os.path.isfile(path)  # not where the program failed before it started its records
    t0, ready = float(open(os.path.join(work, v.replace(":", "-"), "t0")).read()), compiled_at(path) if made else None
    found.setdefault(v, {})[prog] = {"compile_s": compile_seconds(path) if made else None,
                                     "ready_s": None if ready is None else ready - t0,
                                     "reports": training_rates(path) if made else []}
out = os.path.join(os.environ.get("OUT", "."), "mps-pair.json")
device = os.popen("nvidia-smi --query-gpu=name,driver_version --format=csv,noheader").read().strip()
json.dump({"device": device, "date": os.popen("date -u +%FT%TZ").read().strip(),
           "each_s": int(os.environ.get("EACH", 270)), "stagger": os.environ.get("STAGGER", "0") == "1",
           "cold": os.environ.get("COLD", "0") == "1",
           "command": " ".join([f"STAGGER={os.environ.get('STAGGER', '0')} COLD={os.environ.get('COLD', '0')} "
                                f"EACH={os.environ.get('EACH', 270)} bash scripts/gpu/mps_pair.sh", *variants]),
           "variants": found}, open(out, "w"), indent=1)
for v, progs in found.items():
  print(v, {p: (r["compile_s"], r["ready_s"], [x["steps_per_s"] for x in r["reports"]]) for p, r in progs.items()})
PY

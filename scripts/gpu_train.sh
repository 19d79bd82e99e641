#!/usr/bin/env bash
# On the GPU host: optionally the environment benchmark, then for each TASK and each seed in SEEDS
# (default 0) train with the GPU PPO preset for STEPS environment steps and evaluate on the hardest
# staircase (100 trials). Results go to $OUT: bench_env.json, <task>_s<seed>_train.log,
# <task>_s<seed>_curve.csv, <task>_s<seed>_eval_hardest.json, <task>_s<seed>_run.json and, with
# KEEP_POLICY=1, <task>_s<seed>_policy.tgz (the exported policy and run.json).
# Usage: BENCH=1 SEEDS="0 1 2" TRAIN_ARGS="--set k=v" bash scripts/gpu_train.sh STEPS TASK [TASK ...]
set -uo pipefail
steps=$1; shift
export PYTHONUNBUFFERED=1
if [ "${BENCH:-0}" = 1 ]; then
  python3 scripts/bench_env.py --envs 1024,4096,16384 --reps 3 --out "$OUT/bench_env.json" 2>&1 | grep -v -i "warp\|warn"
fi
for task in "$@"; do
  for seed in ${SEEDS:-0}; do
    name=${task}_s${seed}
    run=/tmp/runs/$name
    rm -rf "$run"
    start=$(date +%s)
    cmd="python3 -m train.run --task $task --preset gpu --steps $steps --seed $seed --out $run ${TRAIN_ARGS:-}"
    echo "command: $cmd" | tee "$OUT/${name}_train.log"
    echo "device: $(nvidia-smi --query-gpu=name --format=csv,noheader | head -1), date: $(date -u +%FT%TZ)" \
      | tee -a "$OUT/${name}_train.log"
    $cmd 2>&1 | grep -v -i "warp\|warn" | tee -a "$OUT/${name}_train.log"
    echo "train wall_s $(( $(date +%s) - start )) (includes compilation)" | tee -a "$OUT/${name}_train.log"
    python3 -m train.evaluate "$run" --trials 100 --scene hardest --out "$OUT/${name}_eval_hardest.json" 2>&1 \
      | grep -v -i "warp\|warn"
    cp "$run/run.json" "$OUT/${name}_run.json"
    [ "${KEEP_POLICY:-0}" = 1 ] && tar czf "$OUT/${name}_policy.tgz" -C "$run" policy run.json
    id=$(python3 -c "import json;print(json.load(open('$run/run.json'))['run_id'])")
    python3 -m train.db --db /tmp/runs/experiments.sqlite export "$id" --csv --out "$OUT/${name}_curve.csv"
  done
done

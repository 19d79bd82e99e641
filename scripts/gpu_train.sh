#!/usr/bin/env bash
# On the GPU host: optionally the environment benchmark, then for each TASK train with the GPU PPO
# preset for STEPS environment steps and evaluate on the hardest staircase (100 trials).
# Results go to $OUT: bench_env.json, <task>_train.log, <task>_curve.csv, <task>_eval_hardest.json,
# <task>_run.json.   Usage: BENCH=1 TRAIN_ARGS="--set k=v" bash scripts/gpu_train.sh STEPS TASK [TASK ...]
set -uo pipefail
steps=$1; shift
export PYTHONUNBUFFERED=1
if [ "${BENCH:-0}" = 1 ]; then
  python3 scripts/bench_env.py --envs 1024,4096,16384 --reps 3 --out "$OUT/bench_env.json" 2>&1 | grep -v -i "warp\|warn"
fi
for task in "$@"; do
  run=/tmp/runs/$task
  rm -rf "$run"
  start=$(date +%s)
  python3 -m train.run --task "$task" --preset gpu --steps "$steps" --out "$run" ${TRAIN_ARGS:-} 2>&1 \
    | grep -v -i "warp\|warn" | tee "$OUT/${task}_train.log"
  echo "train wall_s $(( $(date +%s) - start )) (includes compilation)" | tee -a "$OUT/${task}_train.log"
  python3 -m train.evaluate "$run" --trials 100 --scene hardest --out "$OUT/${task}_eval_hardest.json" 2>&1 \
    | grep -v -i "warp\|warn"
  cp "$run/run.json" "$OUT/${task}_run.json"
  id=$(python3 -c "import json;print(json.load(open('$run/run.json'))['run_id'])")
  python3 -m train.db --db /tmp/runs/experiments.sqlite export "$id" --csv --out "$OUT/${task}_curve.csv"
done

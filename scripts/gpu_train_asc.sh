#!/usr/bin/env bash
# On the GPU host: environment benchmark, then train asc-inc-cog with the GPU PPO preset and
# evaluate on the hardest staircase (100 trials). Results go to $OUT.
# Usage: bash scripts/gpu_train_asc.sh STEPS [EXTRA train.run ARGS...]
set -uo pipefail
steps=${1:-8000000}; shift || true
export PYTHONUNBUFFERED=1
run=/tmp/asc-run
rm -rf "$run" /tmp/runs
if [ "${SKIP_BENCH:-0}" != 1 ]; then
  python3 scripts/bench_env.py --envs 1024,4096,16384 --reps 3 --out "$OUT/bench_env.json" 2>&1 | grep -v -i "warp\|warn"
fi
start=$(date +%s)
python3 -m train.run --task asc-inc-cog --preset gpu --steps "$steps" --out "$run" "$@" 2>&1 \
  | grep -v -i "warp\|warn" | tee "$OUT/train.log"
echo "train wall_s $(( $(date +%s) - start ))" | tee -a "$OUT/train.log"
python3 -m train.evaluate "$run" --trials 100 --scene hardest --out "$OUT/eval_hardest.json" 2>&1 | grep -v -i "warp\|warn"
cp "$run/run.json" "$OUT/run.json"
python3 -m train.db --db /tmp/experiments.sqlite export "$(python3 -c "import json;print(json.load(open('$run/run.json'))['run_id'])")" --csv --out "$OUT/curve.csv"
tar czf "$OUT/policy.tgz" -C "$run" policy

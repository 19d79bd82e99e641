#!/usr/bin/env bash
# Time to solve: from process start to an exported policy that reaches the success threshold on
# the hardest staircase (100 trials), with the default config and `--early-stop success`, for
# seeds SEEDS (default "0 1 2") on GPU $GPU (default 0); each exported policy is then evaluated by
# `train.evaluate --scene hardest` (the same trials as the in-training probe). Budget: STEPS
# (default 4,000,000) if the threshold is never reached.
# Writes $OUT/s<seed>_{train.log,eval_hardest.json}; then
# `python scripts/summarize_time_to_solve.py $OUT` writes time_to_solve.md / .json.
set -uo pipefail
export PYTHONUNBUFFERED=1
task=${TASK:-asc-inc-cog}
device="$(nvidia-smi --query-gpu=name --format=csv,noheader | head -1)"
for seed in ${SEEDS:-0 1 2}; do
  run=/tmp/solve/s$seed
  rm -rf "$run"
  cmd="python3 -m train.run --task $task --preset gpu --steps ${STEPS:-4000000} --early-stop success --seed $seed --out $run --db /tmp/solve/db.sqlite"
  { echo "command: CUDA_VISIBLE_DEVICES=${GPU:-0} $cmd"; echo "device: $device, date: $(date -u +%FT%TZ)"; } > "$OUT/s${seed}_train.log"
  t0=$EPOCHREALTIME
  CUDA_VISIBLE_DEVICES=${GPU:-0} $cmd 2>&1 | grep -v -i "warp\|warn" >> "$OUT/s${seed}_train.log"
  echo "process wall_s $(awk "BEGIN {print $EPOCHREALTIME - $t0}") (process start to exported policy)" >> "$OUT/s${seed}_train.log"
  CUDA_VISIBLE_DEVICES=${GPU:-0} python3 -m train.evaluate "$run" --scene hardest \
    --out "$OUT/s${seed}_eval_hardest.json" --db /tmp/solve/db.sqlite 2>&1 | grep -v -i "warp\|warn" | tail -1
done

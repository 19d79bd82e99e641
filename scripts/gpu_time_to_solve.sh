#!/usr/bin/env bash
# Time to solve: from process start to an exported policy that reaches the success threshold on
# the hardest staircase (100 trials), with the default config and `--early-stop success`, for
# seeds SEEDS (default "0 1 2"); seed i runs on the i-th GPU of GPUS (default "0 1 2"), all at
# once, each with its own empty compilation cache (so every process compiles from scratch).
# Each exported policy is then evaluated by `train.evaluate --scene hardest` (the same trials as
# the in-training probe). Budget: STEPS (default 4,000,000) if the threshold is never reached.
# Writes $OUT/s<seed>_{train.log,eval_hardest.json}; then
# `python scripts/summarize_time_to_solve.py $OUT` writes time_to_solve.md / .json.
set -uo pipefail
export PYTHONUNBUFFERED=1
task=${TASK:-asc-inc-cog}
device="$(nvidia-smi --query-gpu=name --format=csv,noheader | head -1)"
solve() {  # SEED GPU
  local seed=$1 gpu=$2 run=/tmp/solve/s$1
  rm -rf "$run" "/tmp/solve/cache$seed"
  local cmd="python3 -m train.run --task $task --steps ${STEPS:-4000000} --early-stop success --seed $seed --out $run --db /tmp/solve/s$seed.sqlite"
  { echo "command: CUDA_VISIBLE_DEVICES=$gpu $cmd"; echo "device: $device, date: $(date -u +%FT%TZ)"; } > "$OUT/s${seed}_train.log"
  local t0=$EPOCHREALTIME
  CUDA_VISIBLE_DEVICES=$gpu MJX_TRACKS_CACHE=/tmp/solve/cache$seed $cmd 2>&1 | grep -v -i "warp\|warn" >> "$OUT/s${seed}_train.log"
  echo "process wall_s $(awk "BEGIN {print $EPOCHREALTIME - $t0}") (process start to exported policy)" >> "$OUT/s${seed}_train.log"
  CUDA_VISIBLE_DEVICES=$gpu python3 -m train.evaluate "$run" --scene hardest \
    --out "$OUT/s${seed}_eval_hardest.json" --db /tmp/solve/s$seed.sqlite 2>&1 | grep -v -i "warp\|warn" | tail -1
}
mkdir -p /tmp/solve
read -r -a gpus <<< "${GPUS:-0 1 2}"
i=0
for seed in ${SEEDS:-0 1 2}; do
  solve "$seed" "${gpus[$((i % ${#gpus[@]}))]}" &
  i=$((i + 1))
  [ $((i % ${#gpus[@]})) = 0 ] && wait
done
wait

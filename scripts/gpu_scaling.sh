#!/usr/bin/env bash
# On a host with 2 (or 4) GPUs: training throughput of `python -m train.run --preset gpu` on 1, 2
# (and 4) GPUs with 4,096 robots per GPU (weak scaling), and one 2-process jax.distributed run
# (one GPU per process, coordinator on localhost). Logs and the run databases go to $OUT; then
# `python scripts/summarize_scaling.py $OUT` writes $OUT/scaling.json and scaling.md.
# Usage: STEPS=1000000 bash scripts/gpu_scaling.sh [GPU_COUNTS (default "1 2")]
set -uo pipefail
export PYTHONUNBUFFERED=1 NCCL_NVLS_ENABLE=0
steps=${STEPS:-1000000}
task=asc-inc-cog
device="$(nvidia-smi --query-gpu=name --format=csv,noheader | head -1) x $(nvidia-smi -L | wc -l)"
for n in ${1:-1 2}; do
  gpus=$(seq -s, 0 $((n - 1)))
  cmd="python3 -m train.run --task $task --preset gpu --num-envs $((4096 * n)) --steps $((steps * n)) --out /tmp/scale/g$n --db $OUT/g$n.sqlite"
  echo "command: CUDA_VISIBLE_DEVICES=$gpus $cmd" | tee "$OUT/g${n}.log"
  echo "device: $device, date: $(date -u +%FT%TZ)" | tee -a "$OUT/g${n}.log"
  CUDA_VISIBLE_DEVICES=$gpus $cmd 2>&1 | grep -v -i "warp\|warn" | tee -a "$OUT/g${n}.log"
done
if [ "${DISTRIBUTED:-1}" = 1 ]; then
  log=$OUT/dist2.log
  base="python3 -m train.run --task $task --preset gpu --num-envs 8192 --steps $((steps * 2)) --out /tmp/scale/dist2 --db $OUT/dist2.sqlite --coordinator localhost:23456 --num-processes 2"
  echo "command: CUDA_VISIBLE_DEVICES=I $base --process-id I  (I = 0, 1)" | tee "$log"
  echo "device: $device, date: $(date -u +%FT%TZ)" | tee -a "$log"
  CUDA_VISIBLE_DEVICES=1 $base --process-id 1 > "$OUT/dist2_p1.log" 2>&1 &
  CUDA_VISIBLE_DEVICES=0 $base --process-id 0 2>&1 | grep -v -i "warp\|warn" | tee -a "$log"
  wait
  tail -5 "$OUT/dist2_p1.log"
  ls /tmp/scale/dist2 /tmp/scale/dist2/checkpoints | tee -a "$log"
fi

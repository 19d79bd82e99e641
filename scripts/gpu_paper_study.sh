#!/usr/bin/env bash
# On a GPU host: runs configs/studies/paper.yaml (PPO runs on the GPUs, 2 per GPU; the one-robot
# SAC runs on CPU slots) for at most LIMIT seconds (a study stopped by the limit resumes where it
# stopped when started again) and packs the study folder without checkpoints into
# $OUT/paper-study.tgz; then, anywhere: `python -m train.study report paper --root DIR`.
# Usage: LIMIT=540 CPU_SLOTS=20 bash scripts/gpu_paper_study.sh
set -uo pipefail
export PYTHONUNBUFFERED=1 NCCL_NVLS_ENABLE=0
export XLA_FLAGS="--xla_cpu_multi_thread_eigen=false"  # many one-robot CPU runs side by side: one thread each
root=${ROOT:-/tmp/studies}
cmd="python3 -m train.study paper --root $root --slots-per-gpu ${SLOTS_PER_GPU:-2} --cpu-slots ${CPU_SLOTS:-20}"
log=$OUT/study.log
device="$(nvidia-smi --query-gpu=name --format=csv,noheader | head -1) x $(nvidia-smi -L | wc -l)"
{ echo "command: $cmd"; echo "device: $device, $(nproc) CPU cores, date: $(date -u +%FT%TZ)"; } | tee "$log"
timeout -s INT "${LIMIT:-540}" $cmd 2>&1 | tee -a "$log"
python3 -m train.study status paper --root "$root" --runs 2>&1 | tee -a "$log"
cp "$log" "$root/paper/"
tar czf "$OUT/paper-study.tgz" --exclude=checkpoints -C "$root" paper

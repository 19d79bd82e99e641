#!/usr/bin/env bash
# On a GPU host: runs configs/studies/paper.yaml (PPO runs on the GPUs, SLOTS_PER_GPU each; the
# one-robot SAC runs on CPU_SLOTS CPU slots) for at most LIMIT seconds (a study stopped by the
# limit resumes where it stopped when started again). Every 30 s, and at the end, the study folder
# (without checkpoints) and the logs of the attempts still running are packed into
# $OUT/paper-study.tgz; then, anywhere: `python -m train.study report paper --root DIR`.
# Extra arguments go to `python -m train.study`, e.g. --set 'tasks=[asc-inc-cog, asc-uni-cog]'.
# FROM=FOLDER continues a study folder that came back earlier (e.g. results/studies/paper-ppo-part):
# its finished runs are skipped.
# Usage: LIMIT=540 SLOTS_PER_GPU=1 CPU_SLOTS=20 [FROM=FOLDER] bash scripts/gpu_paper_study.sh [ARGS]
set -uo pipefail
export PYTHONUNBUFFERED=1 NCCL_NVLS_ENABLE=0
export XLA_FLAGS="--xla_cpu_multi_thread_eigen=false"  # many one-robot CPU runs side by side: one thread each
root=/tmp/studies
cmd=(python3 -m train.study paper --root "$root" --slots-per-gpu "${SLOTS_PER_GPU:-1}" --cpu-slots "${CPU_SLOTS:-20}" "$@")
log=$OUT/study.log
if [ -n "${FROM:-}" ]; then mkdir -p "$root" && rm -rf "$root/paper" && cp -r "$FROM" "$root/paper"; fi
device="$(nvidia-smi --query-gpu=name --format=csv,noheader | head -1) x $(nvidia-smi -L | wc -l)"
{ echo "command: ${cmd[*]}"; echo "device: $device, $(nproc) CPU cores, date: $(date -u +%FT%TZ)"; } | tee "$log"
pack() {
  cp "$log" "$root/paper/" 2>/dev/null
  (cd /tmp && tar czf "$OUT/paper-study.tgz.tmp" --exclude=checkpoints studies/paper study-cell-*/attempt.log 2>/dev/null)
  mv "$OUT/paper-study.tgz.tmp" "$OUT/paper-study.tgz"
}
(while sleep 30; do pack; done) &
packer=$!
timeout -s INT "${LIMIT:-540}" "${cmd[@]}" 2>&1 | grep -v "distributed.scheduler - ERROR" | tee -a "$log"
kill $packer
python3 -m train.study status paper --root "$root" --runs 2>&1 | tee -a "$log"
pack

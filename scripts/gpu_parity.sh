#!/usr/bin/env bash
# Parity of train.run's PPO (or SAC: ALGO=sac) with Brax's ppo.train / sac.train
# (train.brax_reference), same preset (gpu) and budget (STEPS, default 2,000,000), seeds SEEDS
# (default "0 1 2"); each policy is evaluated on the
# hardest staircase (100 trials). With 2 GPUs (PAIRED=1, default), the first of GPUS (default
# "0 1") runs ours and the second Brax's, side by side; with PAIRED=0 both run one after the other
# on the first. ONLY=ours or ONLY=brax runs that trainer's seeds alone, on the first of GPUS.
# Writes $OUT/<impl>_s<seed>_{train.log,eval_hardest.json}; then
# `python scripts/summarize_parity.py $OUT` writes parity.md / parity.json.
set -uo pipefail
export PYTHONUNBUFFERED=1 NCCL_NVLS_ENABLE=0
steps=${STEPS:-2000000}
task=${TASK:-asc-inc-cog}
algo=${ALGO:-ppo}
device="$(nvidia-smi --query-gpu=name --format=csv,noheader | head -1)"
pipeline() {  # IMPL GPU: train and evaluate each seed
  local impl=$1 gpu=$2 module
  [ "$impl" = ours ] && module=train.run || module=train.brax_reference
  for seed in ${SEEDS:-0 1 2}; do
    local name=${impl}_s${seed} run=/tmp/parity/${impl}_s${seed}
    local cmd="python3 -m $module --task $task --algo $algo --preset gpu --steps $steps --seed $seed --out $run"
    { echo "command: CUDA_VISIBLE_DEVICES=$gpu $cmd"; echo "device: $device, date: $(date -u +%FT%TZ)"; } > "$OUT/${name}_train.log"
    local t0=$(date +%s)
    [ "$impl" = ours ] && cmd="$cmd --db /tmp/parity/db.sqlite"
    CUDA_VISIBLE_DEVICES=$gpu $cmd 2>&1 | grep -v -i "warp\|warn" >> "$OUT/${name}_train.log"
    echo "train wall_s $(( $(date +%s) - t0 )) (includes compilation)" >> "$OUT/${name}_train.log"
    CUDA_VISIBLE_DEVICES=$gpu python3 -m train.evaluate "$run" --trials 100 --scene hardest \
      --out "$OUT/${name}_eval_hardest.json" --db /tmp/parity/eval.sqlite 2>&1 | grep -v -i "warp\|warn" | tail -1
  done
}
mkdir -p /tmp/parity
read -r gpu_a gpu_b <<< "${GPUS:-0 1}"
if [ -n "${ONLY:-}" ]; then
  pipeline "$ONLY" "$gpu_a"
elif [ "${PAIRED:-1}" = 1 ]; then
  pipeline ours "$gpu_a" &
  pipeline brax "$gpu_b"
  wait
else
  pipeline ours "$gpu_a"
  pipeline brax "$gpu_a"
fi

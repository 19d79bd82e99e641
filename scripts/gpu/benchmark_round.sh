#!/usr/bin/env bash
# On a GPU host (one GPU): the baselines of the paper's and the hard-tier tasks (train.bench
# baselines), and PPO on des-inc-ang with the length-neutral safety penalty at two scales, all side
# by side (each process gets a fifth of the GPU's memory); every run stopped by `timeout` keeps its
# checkpoint and exported policy; then each trained policy on the hardest staircase (100 trials).
# Results: $OUT/*.json and $OUT/runs.tgz (run folders without checkpoints).
# Usage: LIMIT=420 STEPS=2000000 bash scripts/gpu/benchmark_round.sh
set -uo pipefail
export PYTHONUNBUFFERED=1 XLA_PYTHON_CLIENT_MEM_FRACTION=0.18 MJX_TRACKS_CACHE=/tmp/jaxcache
limit=${LIMIT:-420}; steps=${STEPS:-2000000}; runs=/tmp/runs
mkdir -p "$runs"
python3 -m train.bench baselines --tasks asc-inc-cog,asc-uni-cog,des-inc-ang,des-uni-ang,asc-hard,des-hard \
  --out "$OUT/baselines.json" > "$OUT/baselines.log" 2>&1 &
train() {  # NAME TASK ARGS...
  local name=$1 task=$2; shift 2
  timeout -s TERM "$limit" python3 -m train.run --task "$task" --steps "$steps" --out "$runs/$name" \
    --db "$runs/experiments.sqlite" "$@" > "$runs/$name.log" 2>&1
  python3 -m train.evaluate "$runs/$name" --scene hardest --trials 100 --db "$runs/experiments.sqlite" >> "$runs/$name.log" 2>&1
}
train des-mean1 des-inc-ang --seed 0 --early-stop none --set reward.safety_form=episode_mean --set reward.angular_scale=1.0 &
train des-mean3 des-inc-ang --seed 0 --early-stop none --set reward.safety_form=episode_mean --set reward.angular_scale=3.0 &
train asc-hard asc-hard --seed 0 --steps 8000000 --early-stop success &
wait
for f in "$runs"/*.log; do tail -3 "$f"; done
tar czf "$OUT/runs.tgz" -C /tmp --exclude=checkpoints runs

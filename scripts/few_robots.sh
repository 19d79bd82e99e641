#!/usr/bin/env bash
# The paper's regime: SAC (paper preset: 2 x 64, one robot), on the JAX backend BACKEND (gpu or
# cpu, default gpu), STEPS control steps (default the preset's 20,000), seed 0, the preset's
# evaluations and hardest-staircase probes included. Writes $OUT/few_<backend>.log with the
# command, device, date, the run's output and its process wall time; the [train] lines give the
# training rate (evaluation time left out), the wall time the whole run's.
set -uo pipefail
export PYTHONUNBUFFERED=1
backend=${BACKEND:-gpu}
run=/tmp/few/$backend
rm -rf "$run"
mkdir -p /tmp/few
steps=${STEPS:-20000}
cmd="python3 -m train.run --task asc-inc-cog --algo sac --preset paper --steps $steps --out $run --db /tmp/few/$backend.sqlite"
log="$OUT/few_$backend.log"
platform=""  # the GPU is JAX's default where there is one
if [ "$backend" = cpu ]; then platform=cpu; device="$(lscpu | grep 'Model name' | sed 's/ *Model name: *//'), $(nproc) cores"
else device="$(nvidia-smi --query-gpu=name --format=csv,noheader | head -1)"; fi
{ echo "command: JAX_PLATFORMS=$platform $cmd"; echo "device: $device, date: $(date -u +%FT%TZ)"; } > "$log"
t0=$EPOCHREALTIME
JAX_PLATFORMS=$platform MJX_TRACKS_CACHE=/tmp/few/cache_$backend $cmd 2>&1 | grep -v -i "warp\|warn" >> "$log"
echo "process wall_s $(awk "BEGIN {print $EPOCHREALTIME - $t0}") for $steps control steps" >> "$log"

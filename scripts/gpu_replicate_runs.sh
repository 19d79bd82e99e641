#!/usr/bin/env bash
# On a GPU host: trains again, side by side, the runs of one study cell per seed with the study's
# command (python -m train.run --task TASK --preset gpu --steps STEPS --seed S), then evaluates each
# on every scene of its task's evaluation suite, or on SCENES (each scene in its own process, all at
# once: mind the host's memory, about 2 GB a process), packing
# the run folders without checkpoints into $OUT/replicas-$TASK.tgz every 20 s and at the end.
# For evaluating a study's runs on scenes added after their policies were lost.
# Usage: TASK=mixed-terrain SEEDS="0 1 2" STEPS=500000 LIMIT=480 [SCENES="hardest ..."] bash scripts/gpu_replicate_runs.sh
set -uo pipefail
export PYTHONUNBUFFERED=1 XLA_PYTHON_CLIENT_PREALLOCATE=false
task=${TASK:?TASK=...}; root=/tmp/replicas/$task; mkdir -p "$root"
end=$((SECONDS + ${LIMIT:-480}))
pack() {  # a file written meanwhile makes tar exit 1; the pack is still whole up to it
  tar czf "$OUT/replicas-$task.tgz.tmp" --exclude=checkpoints -C /tmp/replicas "$task" 2>/dev/null
  mv -f "$OUT/replicas-$task.tgz.tmp" "$OUT/replicas-$task.tgz"
}
scenes=${SCENES:-$(python3 -c "from mjx_tracks.envs.config import load_config; from train.evaluate import suite_scenes; print(' '.join(suite_scenes(load_config('$task'))))")}
{ echo "device: $(nvidia-smi --query-gpu=name --format=csv,noheader | head -1) x $(nvidia-smi -L | wc -l), date: $(date -u +%FT%TZ)"; echo "scenes: $scenes"; } | tee "$root/replicas.log"
for s in ${SEEDS:-0 1 2}; do
  ( timeout $((end - SECONDS)) python3 -m train.run --task "$task" --preset gpu --steps "${STEPS:-500000}" --seed "$s" \
      --out "$root/s$s" --db "$root/runs.sqlite" > "$root/train-s$s.log" 2>&1
    for sc in $scenes; do
      timeout $((end - SECONDS)) python3 -m train.evaluate "$root/s$s" --scene "$sc" --trials 100 --db "$root/runs.sqlite" \
        >> "$root/eval-s$s.log" 2>&1 &
    done; wait ) &
done
while [ $SECONDS -lt $end ] && [ -n "$(jobs -r)" ]; do sleep 20; pack; done
wait; pack; grep -h "trials, progress" "$root"/eval-s*.log | cut -c1-160

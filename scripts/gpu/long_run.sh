#!/usr/bin/env bash
# On a GPU host: one long `train.run` in its own process session, so it goes on between calls while
# the machine stays warm; a later call resumes it from /tmp/runs/NAME if the process is gone. Each
# call waits WAIT seconds (or until the run ends), then packs the run folder without checkpoints
# into $OUT/NAME.tgz. Usage: WAIT=500 bash scripts/gpu/long_run.sh NAME TASK STEPS [train.run ARGS]
set -uo pipefail
name=$1 task=$2 steps=$3; shift 3
export PYTHONUNBUFFERED=1 MJX_TRACKS_CACHE=${MJX_TRACKS_CACHE:-/tmp/jaxcache}
runs=/tmp/runs; out=$runs/$name; pidfile=$runs/$name.pid
mkdir -p "$runs"
running() { [ -f "$pidfile" ] && kill -0 "$(cat "$pidfile")" 2>/dev/null; }
if ! running; then
  if [ -d "$out/checkpoints" ]; then args=(--resume "$out" --steps "$steps"); else args=(--task "$task" --steps "$steps" --out "$out" "$@"); fi
  setsid python3 -m train.run "${args[@]}" --db "$runs/experiments.sqlite" >> "$runs/$name.log" 2>&1 < /dev/null &
  echo $! > "$pidfile"
fi
end=$((SECONDS + ${WAIT:-500}))
while [ $SECONDS -lt $end ] && running; do sleep 15; done
tail -3 "$runs/$name.log"
tar czf "$OUT/$name.tgz" -C "$runs" --exclude=checkpoints "$name" "$name.log"

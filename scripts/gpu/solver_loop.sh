#!/usr/bin/env bash
# On a GPU host: MJX's constraint solver as MJX runs it (solver.solve: a while loop whose condition the
# GPU reads back to the host after every Newton pass) against mjx_private.solve (the same passes in a
# loop of fixed length; the same figures bit for bit, tests/test_mjx_private.py), one after the other,
# each variant with a compilation cache of its own, empty at the start:
#   1. python -m train.bench env --envs 40,4096: the batched environment step's rate;
#   2. the paper study's SAC program (its 40 one-robot runs, the pack `python -m train.study paper-packed
#      --plan` prints) for 2,000 steps, no evaluation: its training steps/s and compile s (its database).
# The "while" variant sets mjx_private.solve = solver.solve before anything is traced.
# Writes $OUT/solver-loop.json (and $OUT/logs.txt: each command's last lines), the rest under /tmp/solver-loop (a
# device call brings back at most 8 files). Usage: bash scripts/gpu/solver_loop.sh
set -euo pipefail
export PYTHONUNBUFFERED=1 OUT=${OUT:-.} W=/tmp/solver-loop
rm -rf "$W" /tmp/solver-loop-while /tmp/solver-loop-fixed  # a warm machine keeps /tmp: empty caches
mkdir -p "$W"
WHILE='from mujoco.mjx._src import solver; from mjx_tracks.sim import mjx_private; mjx_private.solve = solver.solve;'
run() {  # SECONDS VARIANT MODULE ARGS...: `python -m MODULE ARGS` with the variant's solver, cut after SECONDS
  local seconds=$1 variant=$2 module=$3; shift 3
  local pre=""; [ "$variant" = while ] && pre=$WHILE
  MJX_TRACKS_CACHE=/tmp/solver-loop-$variant timeout "$seconds" python3 -c "import runpy, sys; $pre sys.argv[0] = '$module'; runpy.run_module('$module', run_name='__main__', alter_sys=True)" "$@"
}
args=$(python3 scripts/gpu/pack_args.py sac)
read -ra SAC <<< "$args"
echo "${SAC[@]}" > "$W/sac-args.txt"
for v in while fixed; do
  run "${ENV_S:-150}" $v train.bench env --envs 40,4096 --reps 20 \
    --out "$W/env-$v.json" > "$W/env-$v.log" 2>&1 || echo "env $v: exit $?" >> "$W/failures.txt"
done
for v in while fixed; do
  s=$(date +%s.%N)
  run "${SAC_S:-220}" $v train.run "${SAC[@]}" --steps 2000 --hp num_evals=1 \
    --hp training_metrics_steps=500 --probe-every 0 --out "$W/run-$v" --db "$W/sac-$v.sqlite" \
    > "$W/sac-$v.log" 2>&1 || echo "sac $v: exit $?" >> "$W/failures.txt"
  echo "$v $(python3 -c "print(round($(date +%s.%N)-$s,1))")" >> "$W/sac-walls.txt"
done
python3 - <<'PY'
import json, os, subprocess
from train.bench.runs import compile_seconds, steady_rate, training_rates
out, w = os.environ["OUT"], os.environ["W"]; res = {"env": {}, "sac": {}}
for v in ("while", "fixed"):
  p = f"{w}/env-{v}.json"
  res["env"][v] = json.load(open(p))["rows"] if os.path.exists(p) else None
walls = dict(l.split() for l in open(f"{w}/sac-walls.txt"))
for v in ("while", "fixed"):
  db = f"{w}/sac-{v}.sqlite"
  try:
    rates = training_rates(db)
    res["sac"][v] = {"wall_s": float(walls[v]), "compile_s": compile_seconds(db), "rates": rates,
                     "steady_steps_per_s": steady_rate(rates)}
  except Exception as e:  # noqa: BLE001
    res["sac"][v] = {"error": repr(e)}
  print(v, res["sac"][v])
dev = subprocess.run(["nvidia-smi", "--query-gpu=name,driver_version", "--format=csv,noheader"], capture_output=True, text=True).stdout.strip()
json.dump({"device": dev, "date": subprocess.run(["date", "-u", "+%FT%TZ"], capture_output=True, text=True).stdout.strip(),
           "command": "bash scripts/gpu/solver_loop.sh", "sac_args": open(f"{w}/sac-args.txt").read().strip(),
           "failures": open(f"{w}/failures.txt").read() if os.path.exists(f"{w}/failures.txt") else "", **res},
          open(f"{out}/solver-loop.json", "w"), indent=1)
PY
for f in "$W"/*.log; do echo "== $f"; tail -n 5 "$f"; done > "$OUT/logs.txt"

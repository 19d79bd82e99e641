#!/usr/bin/env bash
# On a GPU host: what Brax's in-training evaluator costs the paper study's SAC program (its 40 one-robot
# runs in one program, the pack `python -m train.study paper-packed --plan` prints): the program for
# 3,000 steps with no evaluation (--hp num_evals=1) and with 5 (num_evals=6: every 600 steps), one after
# the other, sharing the compilation cache /tmp/sac-cache. Writes $OUT/sac-evals.json: per variant its
# wall s, evaluations, compile s, steady training steps/s and training clock at its last step, read from
# its database (train.bench.runs). Measured: results/speed/group/sac-evals-H200-2026-11-29.json.
# Usage: bash scripts/gpu/sac_evals.sh
set -euo pipefail
export PYTHONUNBUFFERED=1 MJX_TRACKS_CACHE=/tmp/sac-cache OUT=${OUT:-.}
args=$(python3 scripts/gpu/pack_args.py sac)
read -ra A <<< "$args"
echo "${A[@]}" > "$OUT/args.txt"
rm -f "$OUT/walls.txt"
for n in 1 6; do
  d=$OUT/e$n-$RANDOM; mkdir -p "$d"; s=$(date +%s.%N)
  python3 -m train.run "${A[@]}" --steps 3000 --hp num_evals=$n --probe-every 0 --out "$d/run" --db "$d/db.sqlite" \
    > "$d.log" 2>&1
  echo "$n $(python3 -c "print(round($(date +%s.%N)-$s,1))")" >> "$OUT/walls.txt"; rm -rf "$d/run"
done
python3 - <<'PY'
import glob, json, os, sqlite3, subprocess
from train.bench.runs import compile_seconds, training_rates, steady_rate
out = os.environ["OUT"]; rows = []
walls = [l.split() for l in open(f"{out}/walls.txt")]
for (n, wall), db in zip(walls, sorted(glob.glob(f"{out}/e*-*/db.sqlite"), key=os.path.getmtime)):
  c = sqlite3.connect(db)
  evals = c.execute("select count(distinct step) from stats where source='eval'").fetchone()[0]
  rows.append({"num_evals": int(n), "wall_s": float(wall), "eval_reports": evals, "compile_s": compile_seconds(db),
               "steady_steps_per_s": steady_rate(training_rates(db)), "last_clock_s": training_rates(db)[-1]["clock_s"]})
  print(rows[-1])
dev = subprocess.run(["nvidia-smi", "--query-gpu=name,driver_version", "--format=csv,noheader"], capture_output=True, text=True).stdout.strip()
json.dump({"device": dev, "date": subprocess.run(["date", "-u", "+%FT%TZ"], capture_output=True, text=True).stdout.strip(),
           "command": "bash scripts/gpu/sac_evals.sh", "rows": rows}, open(f"{out}/sac-evals.json", "w"), indent=1)
PY

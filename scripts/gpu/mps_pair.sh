#!/usr/bin/env bash
# On a GPU host: the paper study's two programs (configs/studies/paper-packed.yaml: the SAC program of
# 40 one-robot runs, the PPO program of 20 runs x 4,096 robots) side by side on one GPU under a CUDA
# MPS daemon of this script's own, once per VARIANT, each for EACH seconds (default 270, compilation
# included: ~90 s from an empty cache, less from the shared one in /tmp/mps-pair-cache). A VARIANT is
# SHARE:PRIORITY for the PPO program: its CUDA_MPS_ACTIVE_THREAD_PERCENTAGE (85: train.study's) and its
# CUDA_MPS_CLIENT_PRIORITY (0 normal, 1 below normal: NVIDIA's MPS manual); the SAC program runs at
# 85 % and priority 0, as train.study starts it. Writes $OUT/mps-pair.json: each variant's training
# steps/s per run at each report of each program (the median over its runs' [train] lines), and
# prints it. Figures are comparable within one call (one machine); alone: PPO 6,230, SAC ~37 (2026-11-28).
# Usage: EACH=270 bash scripts/gpu/mps_pair.sh 85:0 85:1
set -uo pipefail
export PYTHONUNBUFFERED=1 MJX_TRACKS_CACHE=/tmp/mps-pair-cache XLA_PYTHON_CLIENT_MEM_FRACTION=0.45
tasks=asc-inc-cog,asc-uni-cog,des-inc-ang,des-uni-ang
sac=(python3 -m train.run --tasks $tasks --seeds 0,1,2,3,4 --early-stops return,none --algo sac --preset paper
     --hp max_replay_size=20000 --steps 20000 --compile-ahead on)
ppo=(python3 -m train.run --tasks $tasks --seeds 0,1,2,3,4 --algo ppo --preset gpu --steps 2000000
     --early-stop none --compile-ahead on)
work=/tmp/mps-pair
for variant in "$@"; do
  [[ $variant =~ ^[0-9]+:[01]$ ]] || { echo "error: a variant is SHARE:PRIORITY (e.g. 85:1), got '$variant'" >&2; exit 2; }
done
[ $# -gt 0 ] || { echo "usage: EACH=270 bash scripts/gpu/mps_pair.sh SHARE:PRIORITY ..." >&2; exit 2; }
for variant in "$@"; do
  share=${variant%%:*} priority=${variant#*:}
  dir=$work/$share-$priority && rm -rf "$dir" && mkdir -p "$dir/pipe" "$dir/log"
  export CUDA_MPS_PIPE_DIRECTORY=$dir/pipe CUDA_MPS_LOG_DIRECTORY=$dir/log
  nvidia-cuda-mps-control -d || { echo "error: no MPS daemon for $variant" >&2; exit 1; }
  CUDA_MPS_ACTIVE_THREAD_PERCENTAGE=85 CUDA_MPS_CLIENT_PRIORITY=0 timeout "${EACH:-270}" \
    "${sac[@]}" --out "$dir/sac" > "$dir/sac.log" 2>&1 &
  CUDA_MPS_ACTIVE_THREAD_PERCENTAGE=$share CUDA_MPS_CLIENT_PRIORITY=$priority timeout "${EACH:-270}" \
    "${ppo[@]}" --out "$dir/ppo" > "$dir/ppo.log" 2>&1 &
  wait
  echo quit | nvidia-cuda-mps-control
  echo "$variant: $(grep -h "compiled in" "$dir"/*.log | tr '\n' ' ')"
done
python3 - "$work" "$@" <<'PY'
import json, os, re, statistics, sys
work, variants, found = sys.argv[1], sys.argv[2:], {}
line = re.compile(r"\[train\]\s+([\d,]+)/[\d,]+ .*?\)\s+([\d,]+) steps/s.*\| (\d+) s, eta")
for v in variants:
  for prog in ("sac", "ppo"):
    by_step = {}
    for m in map(line.search, open(os.path.join(work, v.replace(":", "-"), f"{prog}.log"), errors="replace")):
      if m:
        by_step.setdefault(int(m[1].replace(",", "")), []).append((int(m[2].replace(",", "")), int(m[3])))
    found.setdefault(v, {})[prog] = [
        {"step": s, "clock_s": max(c for _, c in r), "steps_per_s": statistics.median(x for x, _ in r)}
        for s, r in sorted(by_step.items())]
out = os.path.join(os.environ.get("OUT", "."), "mps-pair.json")
device = os.popen("nvidia-smi --query-gpu=name,driver_version --format=csv,noheader").read().strip()
json.dump({"device": device, "date": os.popen("date -u +%FT%TZ").read().strip(),
           "each_s": int(os.environ.get("EACH", 270)), "command": " ".join(["bash scripts/gpu/mps_pair.sh", *variants]),
           "variants": found}, open(out, "w"), indent=1)
for v, progs in found.items():
  print(v, {p: [r["steps_per_s"] for r in rows] for p, rows in progs.items()})
PY

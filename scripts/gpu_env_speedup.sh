#!/usr/bin/env bash
# Environment throughput of this tree against an earlier commit, side by side on one GPU in one
# run: each tree's own scripts/bench_env.py (asc-inc-cog, ENVS robots, default 16384), ROUNDS
# rounds (default 2) alternating base and head, REPS timed steps each (default 10).
# The base tree is unpacked beforehand where git is (it is carried to the GPU host, git-ignored):
#   mkdir -p .bench/2cd4a3a && git archive 2cd4a3a | tar -x -C .bench/2cd4a3a
# BASE (default .bench/2cd4a3a). Writes $OUT/speedup/{base,head}_r<k>.json; then
# `python scripts/summarize_env_speedup.py $OUT/speedup` writes env_speedup.md / .json.
set -uo pipefail
base=$(cd "${BASE:-.bench/2cd4a3a}" 2>/dev/null && pwd)
[ -n "$base" ] && [ -d "$base/mjx_tracks" ] || { echo "no base tree in ${BASE:-.bench/2cd4a3a} (see the header of $0)"; exit 2; }
mkdir -p "$OUT/speedup"
head=$PWD
sitepath=${PYTHONPATH:-}
bench() {  # TREE NAME
  (cd "$1" && PYTHONPATH="${sitepath/$head/$1}" python3 scripts/bench_env.py --envs "${ENVS:-16384}" \
    --reps "${REPS:-10}" --out "$OUT/speedup/$2.json" 2>&1 | grep -v -i "warp\|warn" | tail -1)
}
for r in $(seq 1 "${ROUNDS:-2}"); do
  echo "round $r: base $(bench "$base" "base_r$r")"
  echo "round $r: head $(bench "$head" "head_r$r")"
done

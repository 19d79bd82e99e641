#!/usr/bin/env bash
# The robustness suite's policies under a harsher grid than evaluation.robustness's default (the
# cases below, each alone, on the task's hardest scene): every RUN folder given (and the full-throttle
# baseline of each task given with TASKS) evaluated in its own process, all side by side, each run's
# policy copied to $OUT/harsh/NAME and its reports written beside it (eval-hardest+CASE.json), all
# packed into $OUT/harsh.tgz at the end (policies left out). TRIALS (default 100). SCENES (default:
# every case below) picks cases by name, e.g. SCENES="friction-0.7 mass-minus-30". PARALLEL: the
# most processes at once (default all). Runs on a CPU too. The table afterwards:
# python scripts/analysis/harsh_grid_table.py $OUT/harsh --json FILE
# Usage: [TRIALS=100] [TASKS="asc-inc-cog"] [SCENES=...] [PARALLEL=N] bash scripts/gpu/harsh_grid.sh RUN [RUN ...]
set -uo pipefail
export XLA_PYTHON_CLIENT_PREALLOCATE=false  # many processes on one GPU
f() { echo "\"randomization.friction_along=[$1, $1]\", \"randomization.friction_across=[$1, $1]\""; }
cases="[{name: friction-0.7, set: [$(f 0.7)]}, {name: friction-0.6, set: [$(f 0.6)]},
 {name: mass-minus-30, set: [\"randomization.mass=[0.7, 0.7]\"]}, {name: mass-plus-40, set: [\"randomization.mass=[1.4, 1.4]\"]},
 {name: noise-x4, set: [\"randomization.imu_noise=[0.04, 0.2, 0.2]\", \"randomization.imu_bias=[0.08, 0.08]\",
   \"randomization.joint_noise=0.04\", \"randomization.joint_bias=0.08\", \"randomization.depth_noise=0.08\", \"observation.noise=0.4\"]},
 {name: camera-up-10, set: [\"randomization.camera_pitch=[-0.1745, -0.1745]\"]}]"
names=(${SCENES:-friction-0.7 friction-0.6 mass-minus-30 mass-plus-40 noise-x4 camera-up-10})
scenes=(); for n in "${names[@]}"; do scenes+=(--scene "hardest+$n"); done
out=${OUT:-/tmp}/harsh; mkdir -p "$out"
slot() { while [ "$(jobs -rp | wc -l)" -ge "${PARALLEL:-99}" ]; do sleep 2; done; }
pids=()
for run in "$@"; do
  slot
  name=$(basename "$run"); mkdir -p "$out/$name"; cp -r "$run/run.json" "$run/policy" "$out/$name/"  # reports beside it
  python3 -m train.evaluate "$out/$name" --trials "${TRIALS:-100}" --set "evaluation.robustness=$cases" "${scenes[@]}" \
    --db "$out/$name/eval.sqlite" >"$out/$name/log.txt" 2>&1 &
  pids+=($!)
done
for task in ${TASKS:-}; do
  slot
  mkdir -p "$out/full-$task"
  python3 -m train.evaluate "$out/full-$task" --baseline full --task "$task" --trials "${TRIALS:-100}" \
    --set "evaluation.robustness=$cases" "${scenes[@]}" >"$out/full-$task/log.txt" 2>&1 &
  pids+=($!)
done
failed=0; for p in "${pids[@]}"; do wait "$p" || failed=$((failed + 1)); done
for d in "$out"/*/; do echo "$(basename "$d"): $(ls "$d" | grep -c '^eval-hardest+') reports; $(tail -1 "$d/log.txt")"; done
# what comes back from the device is at most 8 files, each named in letters, digits, '.', '_', '-': one archive
(cd "$out/.." && tar czf harsh.tgz --exclude=policy harsh)
[ "$failed" -eq 0 ] || { echo "error: $failed evaluations failed (their log.txt)" >&2; exit 1; }

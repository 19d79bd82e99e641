#!/usr/bin/env bash
# On a GPU host: runs configs/studies/$STUDY.yaml (default paper; PPO runs on the GPUs,
# SLOTS_PER_GPU each; one-robot SAC runs on CPU_SLOTS CPU slots). The first call on a machine starts the study in its
# own process session (setsid), so it keeps running between calls that follow each other while the
# machine stays warm; every call then waits WAIT seconds (or until the study ends), packing the
# study folder (without checkpoints), its log and the logs of the attempts still running (a pack of
# seeds: its training and evaluation logs, and its ended runs' exported policies and records) into
# $OUT/$STUDY-study.tgz.00, .01, ... (parts of 15 MiB: `cat` them together) every 30 s and at the
# end. Afterwards, anywhere:
# `python -m train.study report $STUDY --root DIR`.
# FROM=FOLDER starts from a study folder that came back earlier (e.g. results/studies/paper):
# its finished runs are skipped. Without FROM, a study folder committed at results/studies/$STUDY
# (its state.json) is where it starts from; FROM=none starts afresh. A study folder already on this
# machine (/tmp/studies/$STUDY, from an earlier call) always continues in place: a call that finds its
# study ended never deletes what it made (FROM and the committed folder are then not used). A study
# still running when the machine goes back resumes the same way from the last pack (its running
# attempts start again).
# The study runs from a copy of the tree made at its start (/tmp/studies/src-$STUDY), so later calls, which
# bring the working tree again, never change the code of a study under way.
# Extra arguments go to `python -m train.study`, e.g. --set 'tasks=[asc-inc-cog, asc-uni-cog]'.
# Usage: [STUDY=paper] WAIT=560 [SLOTS_PER_GPU=1] CPU_SLOTS=20 [FROM=FOLDER] bash scripts/gpu/study.sh [ARGS]
# A lent machine goes back after ~30 s without a call and after 30 minutes held: chain calls at once, and
# a study longer than what is left of the machine's 30 minutes loses its running attempts (their
# checkpoints stay on the machine; a pack's ended runs' policies and records come back, above).
# Programs side by side on one GPU time-slice it (8 SAC packs at once: each 14x slower than alone;
# two 5-seed PPO packs: nothing finished in 18 min). With SLOTS_PER_GPU > 1 the study starts CUDA MPS
# (--mps auto; train.study.mps): the paper study's SAC pack beside its PPO pack then trained at
# 0.54-0.62x its rate alone instead of 0.19x (PPO capped: results/speed/group/paper-packed-mps-1-H200-
# 2026-11-28.md). Where the study notes "no CUDA MPS", keep SLOTS_PER_GPU=1 unless runs are tiny.
set -uo pipefail
export PYTHONUNBUFFERED=1 NCCL_NVLS_ENABLE=0
export XLA_FLAGS="--xla_cpu_multi_thread_eigen=false"  # many one-robot CPU runs side by side: one thread each
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1  # and PyTorch (the sb3 library's runs) one thread each too
study=${STUDY:-paper}
root=/tmp/studies
log=$root/$study.log  # per study, so two studies can run side by side on one machine
pidfile=$root/$study.pid
src=$root/src-$study
cmd=(python3 -m train.study "$study" --root "$root" --slots-per-gpu "${SLOTS_PER_GPU:-1}" --cpu-slots "${CPU_SLOTS:-20}" "$@")

running() { [ -f "$pidfile" ] && kill -0 "$(cat "$pidfile")" 2>/dev/null; }

start() {
  mkdir -p "$root"
  rm -rf "${src:?}" && mkdir "$src" && tar cf - --exclude=./.whl --exclude=./.bench --exclude=./runs . | tar xf - -C "$src"
  local from=${FROM:-}
  if [ -z "$from" ] && [ -f "results/studies/$study/state.json" ]; then from="results/studies/$study"; fi
  if [ -f "$root/$study/state.json" ]; then
    # a study that ran on this machine (finished, or its process gone) continues in place: its
    # folder may hold runs not packed yet, so it is never replaced by FROM or the committed one
    echo "continuing $root/$study in place (its finished runs are skipped; FROM not used)" | tee -a "$log"
  elif [ -n "$from" ] && [ "$from" != none ]; then
    echo "starting from $from (its finished runs are skipped)" | tee -a "$log"
    rm -rf "${root:?}/$study" && cp -r "$from" "$root/$study"
  fi
  device="$(nvidia-smi --query-gpu=name --format=csv,noheader | head -1) x $(nvidia-smi -L | wc -l)"
  { echo "command: ${cmd[*]}"; echo "device: $device, $(nproc --all) CPU cores, date: $(date -u +%FT%TZ)"; } | tee -a "$log"
  local pp=${PYTHONPATH:-}
  PYTHONPATH="${pp//"$PWD"/$src}" setsid bash -c 'cd "'"$src"'" && "$@" 2>&1 | grep --line-buffered -v "distributed.scheduler - ERROR" >>"'"$log"'"' _ "${cmd[@]}" </dev/null >/dev/null 2>&1 &
  sleep 2
  pgrep -o -s $! -x python3 >"$pidfile"  # setsid made the shell a session leader: its sid is its pid
}

pack() {
  cp "$log" "$root/$study/study.log" 2>/dev/null
  # a pack's runs stay in /tmp/study-pack-* until its evaluations end: their exported policies and
  # records come back too, so a machine that goes back mid-evaluation loses no trained policy
  # in parts of at most 15 MiB ($OUT gives back 8 files of at most 16 MiB: a finished 60-run study's
  # folder, without checkpoints, is ~20 MB): join them with `cat STUDY-study.tgz.* > STUDY-study.tgz`
  (cd /tmp && tar czf "$root/$study-study.tgz" --exclude=checkpoints --exclude=tb --exclude=.handoff "studies/$study" \
     study-cell-*/attempt.log study-pack-*/*.log study-pack-*/pack/*/policy study-pack-*/pack/*/*.json 2>/dev/null)
  rm -rf "$root/parts" && mkdir "$root/parts" && split -b 15M -d -a 2 "$root/$study-study.tgz" "$root/parts/$study-study.tgz."
  [ "$(ls "$root/parts" | wc -l)" -le 8 ] || echo "warning: $(ls "$root/parts" | wc -l) parts: \$OUT gives back 8 files" >&2
  rm -f "$OUT/$study-study.tgz".* && mv "$root/parts/"* "$OUT/"  # the parts replaced at once (a call cut midway keeps a whole set)
}

if running; then echo "the study is running (pid $(cat "$pidfile")); waiting ${WAIT:-560} s"; else start; fi
end=$((SECONDS + ${WAIT:-560}))
while [ $SECONDS -lt $end ] && running; do
  sleep 30; pack; grep "\[study\]" "$log" | tail -1
  for f in /tmp/study-pack-*/train.log; do  # a pack: one log for its runs, each line tagged [<stop>] [<task>] s<seed>
    [ -f "$f" ] && grep -a "\[probe\]" "$f" | awk '{k = $0; sub(/ \[probe\].*/, "", k); last[k] = $0} END {for (s in last) print last[s]}'
  done
done
tail -5 "$log"
python3 -m train.study status "$study" --root "$root" --runs 2>&1 | tee "$root/$study/status.txt" | tail -70
pack

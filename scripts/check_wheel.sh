#!/usr/bin/env bash
# Builds the wheel from a copy of the checkout's files (so no build/ is left in the repository),
# installs it (no dependencies: they are already installed) into a folder outside the repository,
# and loads a task from there: the configs must ship as package data.
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir "$tmp/src"
(cd "$repo" && git ls-files -z --cached --others --exclude-standard | xargs -0 tar cf -) | tar xf - -C "$tmp/src"
python3 -m pip wheel -q --no-deps -w "$tmp/dist" "$tmp/src"
python3 -m pip install -q --no-deps --target "$tmp/site" "$tmp"/dist/*.whl
cd "$tmp"
PYTHONPATH="$tmp/site" JAX_PLATFORMS=cpu python3 - "$tmp/site" <<'PY'
import sys
import mjx_tracks
from mjx_tracks.envs.config import available_tasks, load_config
assert mjx_tracks.__file__.startswith(sys.argv[1]), f"imported {mjx_tracks.__file__}, not the wheel"
tasks = available_tasks()
assert "asc-inc-cog" in tasks, tasks
cfg = load_config("asc-inc-cog")
print(f"wheel: {len(tasks)} tasks load from {sys.argv[1]} (asc-inc-cog: {cfg.scene.variant} curriculum)")
PY

#!/usr/bin/env bash
# Builds the wheel from a copy of the checkout's files (so no build/ is left in the repository),
# installs it (no dependencies: they are already installed) into a folder outside the repository,
# and loads a task and a shipped study from there: the configs must ship as package data, and every
# train subpackage must be in the wheel.
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
from mjx_tracks.envs.config import available_tasks, config_dir, load_config
assert mjx_tracks.__file__.startswith(sys.argv[1]), f"imported {mjx_tracks.__file__}, not the wheel"
assert str(config_dir()).startswith(sys.argv[1]), f"configs read from {config_dir()}, not the wheel's"
tasks = available_tasks()
assert "asc-inc-cog" in tasks, tasks
cfg = load_config("asc-inc-cog")
import train.core.algos.ppo, train.study.spec  # noqa: E401  (subpackages are listed in pyproject.toml)
assert train.study.spec.__file__.startswith(sys.argv[1]), train.study.spec.__file__
runs = train.study.spec.cells(train.study.spec.load_study("paper"))
print(f"wheel: {len(tasks)} tasks and the paper study ({len(runs)} runs) load from {sys.argv[1]}")
PY

"""The study runner and the server start runs on the GPU from a process of their own: that process
must never touch a device, or JAX preallocates most of the GPU's memory there and every run it
starts dies out of memory (a module-level jnp.array did so on an H200, 2026-11-26)."""

import os
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]


def test_the_lab_imports_and_loads_every_task_without_touching_a_device():
  """JAX_PLATFORMS names no platform: the first device array (at import or in a config load) fails."""
  code = ("import train.study.__main__, train.study.executor, train.server.app, train.evaluation, mjx_tracks, "
          "scenes.navigation, scenes.staircase, scenes.terrain, scenes.spiral\n"
          "from mjx_tracks.envs.config import load_config, available_tasks\n"
          "for t in available_tasks(): load_config(t)\n"
          "print('ok')")
  env = {**os.environ, "PYTHONPATH": str(ROOT), "JAX_PLATFORMS": "no-such-platform"}
  r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, cwd=ROOT, timeout=300)
  assert r.returncode == 0 and r.stdout.strip() == "ok", r.stderr[-2000:]

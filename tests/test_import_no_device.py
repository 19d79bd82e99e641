"""The study runner and the server start runs on the GPU from a process of their own: that process
must never touch a device, or JAX preallocates most of the GPU's memory there and every run it
starts dies out of memory (a module-level jnp.array did so on an H200, 2026-11-26). The package and a
study's light processes import neither JAX nor MuJoCo."""

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


def test_the_package_registers_its_tasks_and_a_studys_light_processes_start_without_jax_or_mujoco():
  """`import mjx_tracks` registers every task with Gymnasium from the YAML files' names alone, and
  what a study's worker and its stand-in runs import (the run folder's record, the database, the
  worker) loads neither JAX nor MuJoCo: ~0.15 s a process, not ~0.9 s (tests/fake_study_run.py
  starts ~100 of them in the suite)."""
  code = ("import sys, gymnasium, mjx_tracks, train.core.run_record, train.db, train.study.worker\n"
          "from mjx_tracks.envs.task_files import available_tasks\n"
          "assert all(f'mjx_tracks/{t}-v0' in gymnasium.registry for t in available_tasks())\n"
          "print(sorted(m for m in ('jax', 'mujoco', 'brax', 'flax') if m in sys.modules), len(available_tasks()))")
  env = {**os.environ, "PYTHONPATH": str(ROOT)}
  r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, cwd=ROOT, timeout=300)
  assert r.returncode == 0, r.stderr[-2000:]
  loaded, tasks = r.stdout.split()[0], int(r.stdout.split()[-1])
  assert loaded == "[]" and tasks == len(list((ROOT / "configs").glob("*.yaml"))) - 1, r.stdout  # less defaults.yaml

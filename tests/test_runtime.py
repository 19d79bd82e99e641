"""The training runtime on the CPU: SIGTERM / Ctrl-C stop with a checkpoint and the policy, a
second Ctrl-C quits at once, concurrent starts, 2 CPU devices training like one, and (marked
`distributed`, outside the default run: `pytest -m distributed tests`) 2 processes doing so."""

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from helpers import TRAIN_TINY, checkpoint_steps, run_id, start_training, wait_for
from train import db as dbmod
from train.core.checkpoints import RunCheckpoints

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def test_sigterm_stops_after_an_update_with_checkpoint_policy_and_exit_143(tmp_path):
  out, database = str(tmp_path / "run"), str(tmp_path / "db.sqlite")
  log = str(tmp_path / "log")
  proc = start_training([*TRAIN_TINY, "--steps", "1000000", "--out", out, "--db", database], log)
  wait_for(lambda: "[train]" in open(log).read(), proc, 300, "progress line")
  proc.send_signal(signal.SIGTERM)
  assert proc.wait(120) == 143
  text = open(log).read()
  assert f"continue with: python -m train.run --resume {out}" in text
  steps = checkpoint_steps(out)
  assert steps and 0 < steps[-1] < 1_000_000
  policy = json.load(open(os.path.join(out, "policy", "policy.json")))
  assert policy["step"] == steps[-1]
  d = dbmod.ExperimentDB(database)
  assert d.run(run_id(out))["status"] == "interrupted"
  assert [e["event"] for e in d.events(run_id(out))][-2:] == ["checkpoint", "interrupted"]


_WAITER = """
import sys, time
from train.core.interrupts import StopRequest
with StopRequest() as stop:
  print("ready", flush=True)
  t = time.time()
  while time.time() - t < 60 and stop.requested is None:
    time.sleep(0.01)
  print("requested", stop.requested, stop.exit_code, flush=True)
  time.sleep(60)
"""


def _waiter():
  proc = subprocess.Popen([sys.executable, "-c", _WAITER], cwd=ROOT, stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, text=True)
  assert proc.stdout.readline().strip() == "ready"
  return proc


def test_a_second_ctrl_c_a_second_later_quits_at_once():
  proc = _waiter()
  proc.send_signal(signal.SIGINT)
  assert proc.stdout.readline().startswith("SIGINT: stopping after this update")
  assert proc.stdout.readline().split() == ["requested", str(int(signal.SIGINT)), "130"]
  assert proc.poll() is None  # the first Ctrl-C only asks
  proc.send_signal(signal.SIGINT)  # at once: the same keypress twice, not a decision to quit
  assert proc.stdout.readline().startswith("SIGINT again: still stopping")
  time.sleep(1.1)
  t = time.time()
  proc.send_signal(signal.SIGINT)
  assert proc.wait(10) == 130 and time.time() - t < 5
  assert "second interrupt: exiting at once" in proc.stdout.read()


def test_sigterm_twice_at_once_as_timeout_and_schedulers_send_it_still_saves():
  """`timeout` and batch schedulers signal the process and its group: two SIGTERMs at once. Neither
  that nor later SIGTERMs quit without saving."""
  proc = _waiter()
  proc.send_signal(signal.SIGTERM)
  assert proc.stdout.readline().startswith("SIGTERM: stopping after this update")
  proc.send_signal(signal.SIGTERM)  # (sent together, the kernel may merge the two into one)
  lines = [proc.stdout.readline(), proc.stdout.readline()]
  assert any(line.startswith("SIGTERM again: still stopping") for line in lines), lines
  assert ["requested", str(int(signal.SIGTERM)), "143"] in [line.split() for line in lines]
  time.sleep(1.1)
  proc.send_signal(signal.SIGTERM)
  time.sleep(1.0)
  assert proc.poll() is None  # still working towards its save
  proc.kill()
  proc.wait(10)


_PLAN_AND_START = """
import sys
from train import run
from train.core.plan import plan_run, write_run_json
plan = plan_run(run.parser().parse_args(["--task", "asc-inc-cog", "--preset", "cpu", "--seed", "3"]))
run._start_records(plan, sys.argv[1])
print(plan.run_id)
"""


def test_simultaneous_starts_of_the_same_task_and_seed_get_their_own_runs(tmp_path):
  database = str(tmp_path / "db.sqlite")
  procs = [subprocess.Popen([sys.executable, "-c", _PLAN_AND_START, database], cwd=str(tmp_path),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env={**os.environ, "JAX_PLATFORMS": "cpu", "PYTHONPATH": ROOT}) for _ in range(2)]
  outs = [p.communicate(timeout=120) for p in procs]
  assert all(p.returncode == 0 for p in procs), outs
  ids = [o[0].split()[-1] for o in outs]
  assert ids[0] != ids[1]
  runs = dbmod.ExperimentDB(database).runs()
  assert sorted(r["run_id"] for r in runs) == sorted(ids)
  assert all(os.path.exists(os.path.join(tmp_path, "runs", i, "run.json")) for i in ids)


def _two_processes(out: str, database: str) -> list:
  """The tiny run as 2 jax.distributed processes of one CPU device each (coordinator on localhost)."""
  import socket
  with socket.socket() as sock:
    sock.bind(("localhost", 0))
    port = sock.getsockname()[1]
  return [start_training([*TRAIN_TINY, "--steps", "512", "--out", out, "--db", database,
                          "--coordinator", f"localhost:{port}", "--num-processes", "2", "--process-id", str(i)],
                         f"{out}.p{i}.log") for i in (0, 1)]


def _runs_match(a: str, b: str, step: int, name: str) -> None:
  """Integers (RNG keys, counters, the curriculum's counts) equal; floats equal up to summation
  order, which Adam's sign-like first steps amplify to ~2 x learning rate on near-zero gradients,
  and the rollouts then a little more."""
  one, other = RunCheckpoints(a).arrays(step), RunCheckpoints(b).arrays(step)
  assert one.keys() == other.keys()
  for k in one:
    if one[k].dtype.kind == "f":
      close = np.isclose(other[k], one[k], rtol=5e-2, atol=5e-3)
      # one element of a leaf may differ: a robot's trajectory can part at a contact (chaotic; seen
      # on robot 7 of 16 in one environment leaf, at the landed commit too); two elements fail
      assert close.size - close.sum() <= (1 if close.size >= 16 else 0), (
          f"{name}: {k}: {np.flatnonzero(~close)[:8]} differ: {other[k].ravel()[~close.ravel()][:4]} vs "
          f"{one[k].ravel()[~close.ravel()][:4]}")
    else:
      np.testing.assert_array_equal(other[k], one[k], err_msg=f"{name}: {k}")


def _start_tiny_run(out: str, database: str, devices: int):
  """The ppo_run fixture's training (its first update) on `devices` CPU devices (with the suite's
  compile flags, tests/conftest.py)."""
  flags = f"{os.environ.get('XLA_FLAGS', '')} --xla_force_host_platform_device_count={devices}".strip()
  return start_training([*TRAIN_TINY, "--steps", "512", "--out", out, "--db", database], out + ".log",
                        {"XLA_FLAGS": flags})


def test_two_cpu_devices_train_like_one(ppo_run, tmp_path):
  """The session's tiny run (1 CPU device) and its first update on a mesh of 2 devices."""
  out = str(tmp_path / "d2")
  proc = _start_tiny_run(out, str(tmp_path / "db.sqlite"), 2)
  assert proc.wait(600) == 0, open(out + ".log").read()[-2000:]
  assert "on 2 x cpu" in open(out + ".log").read()
  _runs_match(ppo_run[0], out, 512, "2 devices")


@pytest.mark.distributed
def test_two_processes_train_like_one_device(ppo_run, tmp_path):
  """The same run as 2 jax.distributed processes of one CPU device each (coordinator on
  localhost), which train one policy; process 1 keeps no records."""
  database = str(tmp_path / "db.sqlite")
  out = str(tmp_path / "p2")
  procs = _two_processes(out, database)
  assert [p.wait(600) for p in procs] == [0, 0], open(out + ".p0.log").read()[-2000:]
  assert "on 2 x cpu, 2 processes" in open(out + ".p0.log").read()
  _runs_match(ppo_run[0], out, 512, "2 processes")
  assert len(dbmod.ExperimentDB(database).runs()) == 1

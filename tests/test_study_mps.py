"""CUDA MPS for runs sharing a GPU (train.study.mps), against a stand-in for NVIDIA's control program
that records how it was called: the study's own daemon (a fresh pipe directory), its clients' environment
in the GPU workers only, its stop, and a clear refusal where it cannot start."""

import argparse
import os
import stat

import pytest

from train.study import cluster, mps

FAKE = """#!/bin/sh
echo "args=$* pipe=$CUDA_MPS_PIPE_DIRECTORY log=$CUDA_MPS_LOG_DIRECTORY stdin=$(cat)" >> "$FAKE_MPS_LOG"
echo "$FAKE_MPS_SAYS" >&2
exit ${FAKE_MPS_RC:-0}
"""


@pytest.fixture
def control(tmp_path, monkeypatch):
  """The stand-in on PATH (alone); returns its log's path."""
  bin_dir = tmp_path / "bin"
  bin_dir.mkdir()
  path = bin_dir / mps.CONTROL
  path.write_text(FAKE)
  path.chmod(path.stat().st_mode | stat.S_IEXEC)
  log = tmp_path / "calls.log"
  monkeypatch.setenv("PATH", f"{bin_dir}:/usr/bin:/bin")
  monkeypatch.setenv("FAKE_MPS_LOG", str(log))
  return log


def _args(mode: str, slots: int = 2) -> argparse.Namespace:
  p = argparse.ArgumentParser()
  cluster.add_cluster_args(p)
  return p.parse_args(["--mps", mode, "--slots-per-gpu", str(slots)])


def test_mps_is_wanted_where_runs_share_a_gpu_and_its_control_program_is_there(control, monkeypatch):
  assert mps.wanted("auto", 2, ["0"]) and mps.wanted("on", 1, ["0"])
  assert not mps.wanted("auto", 1, ["0"]) and not mps.wanted("auto", 2, []) and not mps.wanted("off", 4, ["0"])
  with pytest.raises(ValueError, match="--mps takes one of auto, on, off, got 'yes'"):
    mps.wanted("yes", 2, ["0"])
  with pytest.raises(ValueError, match="--mps on: this cluster has no GPU"):
    mps.wanted("on", 2, [])
  with pytest.raises(SystemExit):
    _args("yes")
  monkeypatch.setenv("PATH", "/nonexistent")
  assert not mps.wanted("auto", 2, ["0"])
  with pytest.raises(OSError, match="nvidia-cuda-mps-control is not installed"):
    mps.start()


def test_the_daemon_is_the_studys_own_and_only_the_gpu_workers_runs_use_it(control):
  daemon = mps.start()
  assert os.path.basename(daemon.pipe_dir).startswith("mjx-tracks-mps-") and os.path.isdir(daemon.log_dir)
  assert control.read_text().splitlines() == [f"args=-d pipe={daemon.pipe_dir} log={daemon.log_dir} stdin="]
  env = daemon.client_env()
  assert env == {"CUDA_MPS_PIPE_DIRECTORY": daemon.pipe_dir, "CUDA_MPS_LOG_DIRECTORY": daemon.log_dir,
                 "CUDA_MPS_ACTIVE_THREAD_PERCENTAGE": str(mps.SM_SHARE)}
  specs = cluster.worker_specs(["0", "1"], 2, 3, env)
  for gpu in ("gpu0", "gpu1"):
    got = specs[gpu]["options"]["env"]
    assert {k: got[k] for k in env} == env and got["XLA_PYTHON_CLIENT_MEM_FRACTION"] == "0.45"
  assert not set(env) & set(specs["cpu"]["options"]["env"])
  daemon.stop()
  assert control.read_text().splitlines()[-1] == f"args= pipe={daemon.pipe_dir} log={daemon.log_dir} stdin=quit"
  assert not os.path.exists(daemon.pipe_dir)


def test_a_daemon_that_cannot_start_is_refused_under_on_and_noted_under_auto(control, monkeypatch, capsys):
  made, mkdtemp = [], mps.tempfile.mkdtemp
  monkeypatch.setattr(mps.tempfile, "mkdtemp", lambda **kw: made.append(mkdtemp(**kw)) or made[-1])
  monkeypatch.setenv("FAKE_MPS_RC", "1")
  monkeypatch.setenv("FAKE_MPS_SAYS", "An instance of this daemon is already running")
  with pytest.raises(OSError, match=r"-d failed \(1\): An instance of this daemon is already running"):
    cluster._mps_env(_args("on"), ["0"])  # noqa: SLF001
  assert cluster._mps_env(_args("auto"), ["0"]) is None  # noqa: SLF001
  assert "note: no CUDA MPS" in capsys.readouterr().out
  assert cluster._mps_env(_args("auto", slots=1), ["0"]) is None and len(control.read_text().splitlines()) == 2  # noqa: SLF001
  assert len(made) == 2 and not any(os.path.exists(d) for d in made)  # a failed start leaves no folder


def test_auto_uses_the_daemon_only_where_a_cuda_context_goes_through_it(control, monkeypatch, capsys):
  """This machine has no CUDA driver: the probe's context fails, so the daemon is stopped again and
  auto goes on without it (on refuses); where the probe passes, the workers get its environment and
  the daemon is stopped at exit."""
  daemon = mps.start()
  assert "a CUDA context through it failed (OSError: libcuda.so.1" in mps.client_error(daemon, "0")
  daemon.stop()
  assert cluster._mps_env(_args("auto"), ["0"]) is None  # noqa: SLF001
  assert "note: no CUDA MPS (nvidia-cuda-mps-control: a CUDA context through it failed" in capsys.readouterr().out
  assert control.read_text().splitlines()[-1].endswith("stdin=quit")
  with pytest.raises(OSError, match="a CUDA context through it failed"):
    cluster._mps_env(_args("on"), ["0"])  # noqa: SLF001
  at_exit = []
  monkeypatch.setattr(mps, "client_error", lambda daemon, gpu: None)
  monkeypatch.setattr(cluster.atexit, "register", at_exit.append)
  env = cluster._mps_env(_args("auto"), ["0"])  # noqa: SLF001
  assert env["CUDA_MPS_ACTIVE_THREAD_PERCENTAGE"] == "85" and os.path.isdir(env["CUDA_MPS_PIPE_DIRECTORY"])
  assert "CUDA MPS for 2 runs a GPU, each at most 85 %" in capsys.readouterr().out
  (stop,) = at_exit
  stop()
  assert not os.path.exists(env["CUDA_MPS_PIPE_DIRECTORY"])

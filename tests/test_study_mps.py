"""CUDA MPS for runs sharing a GPU (train.study.mps), against a stand-in for NVIDIA's control program
that records how it was called and writes the daemon's log as the real one does: the study's own daemon
(a fresh pipe directory), its clients' environment in the GPU workers only, its stop, the probe that
a CUDA context went through it, and a clear refusal or note where it cannot be had."""

import argparse
import os
import stat

import pytest

from train.study import cluster, mps

# -d writes the daemon's log's first line; get_server_list / get_client_list answer as the real one does
# (one server, 4242, once a client registered in the pipe folder's file `clients`: the real daemon
# starts its server at its first client)
FAKE = """#!/bin/sh
asked=$(cat)
echo "args=$* pipe=$CUDA_MPS_PIPE_DIRECTORY log=$CUDA_MPS_LOG_DIRECTORY stdin=$asked" >> "$FAKE_MPS_LOG"
case "$asked" in
  get_server_list) if [ -f "$CUDA_MPS_PIPE_DIRECTORY/clients" ]; then echo 4242; fi ;;
  "get_client_list 4242") cat "$CUDA_MPS_PIPE_DIRECTORY/clients" ;;
  *) echo "$FAKE_MPS_SAYS" ;;
esac
if [ "$1" = "-d" ]; then echo "[x Control 1] Starting control daemon" > "$CUDA_MPS_LOG_DIRECTORY/control.log"; fi
exit ${FAKE_MPS_RC:-0}
"""
# a probe whose context the daemon serves (argv[1] == "served": it registers as a client) or not; it
# holds its context until a line comes on stdin, as the real one does
PROBE_PASSES = ("import sys, os\n"
                "if sys.argv[1] == 'served':\n"
                "  open(os.environ['CUDA_MPS_PIPE_DIRECTORY'] + '/clients', 'a').write(f'{os.getpid()}\\n')\n"
                "print('ready', flush=True)\n"
                "sys.stdin.readline()\n")
PROBE_HANGS = "import time; time.sleep(30)"


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


def _args(*argv: str) -> argparse.Namespace:
  p = argparse.ArgumentParser()
  cluster.add_cluster_args(p)
  return p.parse_args(["--slots-per-gpu", "2", *argv])


def test_mps_is_wanted_where_runs_share_a_gpu_and_its_control_program_is_there(control, monkeypatch, capsys):
  assert mps.wanted("auto", 2, ["0"]) and mps.wanted("on", 1, ["0"])
  assert not mps.wanted("auto", 1, ["0"]) and not mps.wanted("auto", 2, []) and not mps.wanted("off", 4, ["0"])
  with pytest.raises(ValueError, match="--mps takes one of auto, on, off, got 'yes'"):
    mps.wanted("yes", 2, ["0"])
  with pytest.raises(ValueError, match="--mps on: this cluster has no GPU"):
    mps.wanted("on", 2, [])
  with pytest.raises(SystemExit):
    _args("--mps", "yes")
  with pytest.raises(ValueError, match="--mps on starts MPS for the workers started here"):
    cluster.make_client(_args("--mps", "on", "--scheduler", "tcp://127.0.0.1:1"))
  monkeypatch.setenv("PATH", "/nonexistent")
  assert cluster._mps(_args(), ["0"]) is None  # noqa: SLF001
  assert ("note: no CUDA MPS (nvidia-cuda-mps-control is not installed (NVIDIA's driver utilities)); the runs "
          "sharing a GPU take turns on it") in capsys.readouterr().out
  with pytest.raises(OSError, match="nvidia-cuda-mps-control is not installed"):
    mps.start()


def test_the_daemon_is_the_studys_own_and_only_the_gpu_workers_runs_use_it(control):
  daemon = mps.start()
  assert os.path.dirname(daemon.pipe_dir) == "/tmp" and os.path.basename(daemon.pipe_dir).startswith("mjx-tracks-mps-")
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
  with pytest.raises(OSError, match=r"-d failed \(1\): An instance of this daemon is already running; "
                                    r"\[x Control 1\] Starting control daemon"):
    cluster._mps(_args("--mps", "on"), ["0"])  # noqa: SLF001
  assert cluster._mps(_args(), ["0"]) is None  # noqa: SLF001
  assert "note: no CUDA MPS" in capsys.readouterr().out
  assert cluster._mps(_args("--slots-per-gpu", "1"), ["0"]) is None and len(control.read_text().splitlines()) == 2  # noqa: SLF001
  assert len(made) == 2 and not any(os.path.exists(d) for d in made)  # a failed start leaves no folder


@pytest.mark.parametrize("probe, served, error", [
    (None, "", "a CUDA context through it failed (OSError: no-such-libcuda.so"),  # the real probe, no driver
    (PROBE_PASSES, "unserved", "the probe's CUDA context did not go through it (the daemon named no such client; "
                               "its log: [x Control 1] Starting"),
    (PROBE_HANGS, "", "a CUDA context through it took over 1 s"),
    (PROBE_PASSES, "served", None)])
def test_the_daemon_is_used_only_where_a_probes_cuda_context_went_through_it(control, monkeypatch, capsys, probe,
                                                                            served, error):
  """A CUDA process that cannot reach the daemon runs without it: while the probe holds its context,
  the daemon must name it among its clients. Where it does not, or the probe fails or hangs, the
  daemon is stopped again and auto goes on without it (on refuses); where it does, the workers get
  its environment, and at exit the cluster closes before it stops."""
  monkeypatch.setattr(mps, "CUDA_LIBRARY", served or "no-such-libcuda.so")
  monkeypatch.setattr(mps, "PROBE_TIMEOUT", 1)
  if probe:
    monkeypatch.setattr(mps, "_CLIENT_PROBE", probe)
  if not error:  # Dask's first import registers exit handlers of its own: before atexit is stood in for
    import distributed  # noqa: F401
  at_exit = []
  monkeypatch.setattr(cluster.atexit, "register", at_exit.append)
  monkeypatch.setattr(cluster.atexit, "unregister", at_exit.remove)
  if not error:
    _the_cluster_started_here_closes_before_its_daemon_stops(monkeypatch, at_exit, capsys)
    return
  assert cluster._mps(_args(), ["0"]) is None and not at_exit  # noqa: SLF001
  assert f"note: no CUDA MPS (nvidia-cuda-mps-control: {error}" in capsys.readouterr().out
  assert control.read_text().splitlines()[-1].endswith("stdin=quit")
  with pytest.raises(OSError, match=error.replace("(", r"\(").replace("[", r"\[")):
    cluster._mps(_args("--mps", "on"), ["0"])  # noqa: SLF001


def _the_cluster_started_here_closes_before_its_daemon_stops(monkeypatch, at_exit, capsys):
  """make_client on GPU 0 (Dask's cluster and client stood in for): the GPU worker's runs get the
  daemon's environment, and exit handlers (run last first) close the cluster, then stop the daemon."""
  import distributed

  class Cluster:
    def __init__(self, specs):
      self.specs = specs

    def close(self):
      pass
  monkeypatch.setattr(cluster, "local_cluster", Cluster)
  monkeypatch.setattr(distributed, "Client", lambda c: c)
  made, kinds = cluster.make_client(_args("--gpus", "0"))
  assert kinds == ("gpu",) and "CUDA MPS for 2 runs a GPU, each at most 85 %" in capsys.readouterr().out
  stop, close = at_exit
  daemon = stop.__self__
  assert close == made.close and stop == daemon.stop
  assert made.specs["gpu0"]["options"]["env"]["CUDA_MPS_PIPE_DIRECTORY"] == daemon.pipe_dir
  stop()
  assert not os.path.exists(daemon.pipe_dir)

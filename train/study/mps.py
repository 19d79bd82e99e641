"""CUDA MPS (the Multi-Process Service) for runs side by side on one GPU.

Without it, programs of several processes on one GPU take turns (time-slicing): beside a PPO program
of 20 runs, the paper study's one-robot SAC program, whose steps are chains of tiny kernels, trained
at 0.19x its rate alone. Under MPS their kernels run at once; with each process kept to SM_SHARE of
the GPU's multiprocessors (CUDA_MPS_ACTIVE_THREAD_PERCENTAGE), a large program leaves the rest free
for the small one's kernels (results/speed/group/paper-packed-mps-1-H200-2026-11-28.md).

The control daemon started here is this study's own: its pipe directory is a fresh folder under
/tmp (a Unix socket's path has at most 108 bytes), and only the processes given `client_env()`
connect to it. It changes no setting of the GPU. A CUDA process that cannot reach the daemon runs
without MPS, silently (NVIDIA's manual), so `client_error` checks that the daemon names a probe's
context among its clients. The cost (NVIDIA's MPS documentation, "Error Containment"): a fatal GPU
fault of one run (an illegal memory access, not an out-of-memory error) reaches every run on that
GPU, and the daemon takes no new run until they have all exited; the study records them failed and
retries them.
"""

from __future__ import annotations

import dataclasses
import os
import select
import shutil
import signal
import subprocess
import sys
import tempfile

CONTROL = "nvidia-cuda-mps-control"  # the daemon's control program (NVIDIA's driver utilities)
CUDA_LIBRARY = "libcuda.so.1"  # the CUDA driver the probe loads
# % of a GPU's multiprocessors one process may use under MPS. One H200, the paper study's PPO program
# (20 runs) beside its SAC program (40 one-robot runs), per-run training steps/s against each alone
# (6,230 / ~37): time-sliced 0.77x / 0.19x; MPS with no share 0.92x / 0.22x; PPO at 85 % 0.87-0.89x /
# 0.54-0.62x; PPO at 60 % 0.70-0.71x / 0.59-0.76x (SAC uncapped; results/speed/group/
# paper-packed-mps-1-H200-2026-11-28.md). The larger program at MPS client priority "below normal"
# (CUDA_MPS_CLIENT_PRIORITY=1) gave SAC 3-6 % (mps-pair-priority-H200-2026-11-28.json): runs keep the default
SM_SHARE = 85
MODES = ("auto", "on", "off")  # --mps: auto tries it where runs share a GPU (a note where it cannot be had)


@dataclasses.dataclass(frozen=True)
class Mps:
  """A running control daemon of this process's cluster."""

  pipe_dir: str
  log_dir: str

  def client_env(self, share: int = SM_SHARE) -> dict[str, str]:
    """What a process needs in its environment to run its kernels through this daemon."""
    return {"CUDA_MPS_PIPE_DIRECTORY": self.pipe_dir, "CUDA_MPS_LOG_DIRECTORY": self.log_dir,
            "CUDA_MPS_ACTIVE_THREAD_PERCENTAGE": str(share)}

  def log(self) -> str:
    """The daemon's own log (its clients, why it refused something), or ''."""
    try:
      with open(os.path.join(self.log_dir, "control.log"), errors="replace") as f:
        return f.read()
    except OSError:
      return ""

  def clients(self) -> set[int]:
    """The pids of the processes whose CUDA contexts go through the daemon now (its answer to
    get_server_list, then get_client_list for each server), or an empty set where it did not answer."""
    return {int(pid) for server in (self._ask("get_server_list") or "").split()
            for pid in (self._ask(f"get_client_list {server}") or "").split() if pid.isdigit()}

  def _ask(self, command: str) -> str | None:
    """The daemon's answer to one command of its control program, or None where the program failed
    or took over 30 s."""
    try:
      done = subprocess.run([CONTROL], input=command + "\n", text=True, env=self._env(), capture_output=True,
                            timeout=30)
    except (OSError, subprocess.TimeoutExpired):
      return None
    return done.stdout if done.returncode == 0 else None

  def log_tail(self, lines: int = 3) -> str:
    return " | ".join(line.strip() for line in self.log().splitlines()[-lines:])

  def stop(self) -> None:
    """Asks the daemon to quit, and ends it (SIGTERM to its pid file's process) where that failed or
    took over 30 s (a client still connected); then removes its folder. Never raises."""
    if self._ask("quit") is None:
      try:
        with open(os.path.join(self.pipe_dir, "nvidia-cuda-mps-control.pid")) as f:
          os.kill(int(f.read().strip()), signal.SIGTERM)
      except (OSError, ValueError):
        pass  # no daemon
    shutil.rmtree(self.pipe_dir, ignore_errors=True)

  def _env(self) -> dict[str, str]:
    return {**os.environ, "CUDA_MPS_PIPE_DIRECTORY": self.pipe_dir, "CUDA_MPS_LOG_DIRECTORY": self.log_dir}


def wanted(mode: str, slots_per_gpu: int, gpus: list[str]) -> bool:
  """Whether to try MPS: `on` wherever there are GPUs, `auto` where runs share one (slots_per_gpu >
  1); ValueError for another mode, or `on` without a GPU. (Whether it can be had: start, client_error.)"""
  if mode not in MODES:
    raise ValueError(f"--mps takes one of {', '.join(MODES)}, got {mode!r}")
  if mode == "on" and not gpus:
    raise ValueError("--mps on: this cluster has no GPU")
  if mode == "off" or not gpus:
    return False
  return mode == "on" or slots_per_gpu > 1


# a CUDA context through the daemon, made by the driver API alone (no JAX), held until a line comes on
# stdin (so the daemon can be asked for its clients meanwhile); prints "ready" where the driver made it,
# else exits 1 with the failing call and CUDA's error code on its last line
_CLIENT_PROBE = """import ctypes, sys
cuda = ctypes.CDLL(sys.argv[1])
dev, ctx = ctypes.c_int(), ctypes.c_void_p()
for name, call in (("cuInit", lambda: cuda.cuInit(0)), ("cuDeviceGet", lambda: cuda.cuDeviceGet(ctypes.byref(dev), 0)),
                   ("cuDevicePrimaryCtxRetain", lambda: cuda.cuDevicePrimaryCtxRetain(ctypes.byref(ctx), dev))):
  code = call()
  if code:
    sys.exit(f"{name}: CUDA error {code}")
print("ready", flush=True)
sys.stdin.readline()
cuda.cuDevicePrimaryCtxRelease(dev)
"""
PROBE_TIMEOUT = 60  # s for the probe's CUDA context (~1 s on an H200 host)


def client_error(mps: Mps, gpu: str) -> str | None:
  """Why a process on GPU `gpu` would not run through the daemon (some hosts' sandboxes have no MPS
  server; a CUDA process that cannot reach it runs without MPS), or None where a probe's context went
  through it: the driver made the context, and while the probe held it the daemon named it among its
  servers' clients. (Not the daemon's log: it reaches its file late, e.g. still empty seconds after a
  client on an H200 host, 2026-11-28.)"""
  env = {**mps._env(), "CUDA_VISIBLE_DEVICES": gpu}  # noqa: SLF001
  probe = subprocess.Popen([sys.executable, "-c", _CLIENT_PROBE, CUDA_LIBRARY], env=env, stdin=subprocess.PIPE,
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
  late = f"a CUDA context through it took over {PROBE_TIMEOUT} s"
  try:
    if not select.select([probe.stdout], [], [], PROBE_TIMEOUT)[0]:
      return late
    ready = probe.stdout.readline().strip() == "ready"
    served = ready and probe.pid in mps.clients()
    _, err = probe.communicate("\n", timeout=PROBE_TIMEOUT)
  except subprocess.TimeoutExpired:
    return late
  finally:
    if probe.poll() is None:
      probe.kill()
      probe.wait()
  if not ready:
    return f"a CUDA context through it failed ({(err.strip().splitlines() or ['no message'])[-1][:200]})"
  if not served:
    return ("the probe's CUDA context did not go through it (the daemon named no such client; its log: "
            f"{mps.log_tail() or 'empty'})")
  return None


def start() -> Mps:
  """Starts a control daemon of its own (a fresh pipe directory); OSError with the reason where it
  cannot (no control program, or it refused to start or hung)."""
  if shutil.which(CONTROL) is None:
    raise OSError(f"{CONTROL} is not installed (NVIDIA's driver utilities)")
  pipe_dir = tempfile.mkdtemp(prefix="mjx-tracks-mps-", dir="/tmp")
  mps = Mps(pipe_dir, os.path.join(pipe_dir, "log"))
  os.makedirs(mps.log_dir)
  said = os.path.join(pipe_dir, "start.out")  # a file, not a pipe: the forked daemon may keep its output open
  try:
    with open(said, "w") as out:
      rc = subprocess.run([CONTROL, "-d"], env=mps._env(), stdin=subprocess.DEVNULL, stdout=out, stderr=out,  # noqa: SLF001
                          timeout=60).returncode
    message = open(said, errors="replace").read().strip()[:200]
  except subprocess.TimeoutExpired:
    rc, message = None, "no answer in 60 s"
  if rc != 0:
    why = "; ".join(x for x in (message, mps.log_tail()) if x)
    shutil.rmtree(pipe_dir, ignore_errors=True)
    raise OSError(f"{CONTROL} -d failed ({rc}): {why}")
  return mps

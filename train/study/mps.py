"""CUDA MPS (the Multi-Process Service) for runs side by side on one GPU.

Without it, programs of several processes on one GPU take turns (time-slicing): beside a PPO program
of 20 runs, the paper study's one-robot SAC program, whose steps are chains of tiny kernels, trained
at 0.19x its rate alone. Under MPS their kernels run at once; with each process kept to SM_SHARE of
the GPU's multiprocessors (CUDA_MPS_ACTIVE_THREAD_PERCENTAGE), a large program leaves the rest free
for the small one's kernels (results/speed/group/paper-packed-mps-1-H200-2026-11-28.md).

The control daemon started here is this study's own: its pipe directory is a fresh temporary folder,
and only the processes given `client_env()` connect to it. It changes no setting of the GPU. The cost
(NVIDIA's MPS documentation, "Error Containment"): a fatal GPU fault of one run (an illegal memory
access, not an out-of-memory error) reaches every run on that GPU, and the daemon takes no new run
until they have all exited; the study records them failed and retries them (its `retries`).
"""

from __future__ import annotations

import dataclasses
import os
import shutil
import subprocess
import sys
import tempfile

CONTROL = "nvidia-cuda-mps-control"  # the daemon's control program (NVIDIA's driver utilities)
# % of a GPU's multiprocessors one process may use under MPS. One H200, the paper study's PPO program
# (20 runs) beside its SAC program (40 one-robot runs), per-run training steps/s against each alone
# (6,230 / ~37): time-sliced 0.77x / 0.19x; MPS with no share 0.92x / 0.2x; PPO at 85 % 0.88x / 0.55x;
# PPO at 60 % 0.71x / 0.65x (results/speed/group/paper-packed-mps-1-H200-2026-11-28.md)
SM_SHARE = 85
MODES = ("auto", "on", "off")  # --mps: auto starts it where runs share a GPU and CONTROL exists


@dataclasses.dataclass(frozen=True)
class Mps:
  """A running control daemon of this process's cluster."""

  pipe_dir: str
  log_dir: str

  def client_env(self, share: int = SM_SHARE) -> dict[str, str]:
    """What a process needs in its environment to run its kernels through this daemon."""
    return {"CUDA_MPS_PIPE_DIRECTORY": self.pipe_dir, "CUDA_MPS_LOG_DIRECTORY": self.log_dir,
            "CUDA_MPS_ACTIVE_THREAD_PERCENTAGE": str(share)}

  def stop(self) -> None:
    """Asks the daemon to quit (it ends its server once its clients are gone); never raises."""
    try:
      subprocess.run([CONTROL], input="quit\n", text=True, env=self._env(), capture_output=True, timeout=30)
    except (OSError, subprocess.TimeoutExpired):
      pass
    shutil.rmtree(self.pipe_dir, ignore_errors=True)

  def _env(self) -> dict[str, str]:
    return {**os.environ, "CUDA_MPS_PIPE_DIRECTORY": self.pipe_dir, "CUDA_MPS_LOG_DIRECTORY": self.log_dir}


def wanted(mode: str, slots_per_gpu: int, gpus: list[str]) -> bool:
  """Whether to start MPS: `on` wherever there are GPUs, `auto` where runs share one (slots_per_gpu
  > 1) and the control program is installed; ValueError for another mode, or `on` without a GPU."""
  if mode not in MODES:
    raise ValueError(f"--mps takes one of {', '.join(MODES)}, got {mode!r}")
  if mode == "on" and not gpus:
    raise ValueError("--mps on: this cluster has no GPU")
  if mode == "off" or not gpus:
    return False
  return mode == "on" or (slots_per_gpu > 1 and shutil.which(CONTROL) is not None)


# a CUDA context through the daemon, made by the driver API alone (no JAX: ~1 s); exit 0 where the
# MPS server took the client, else 1 with the failing call and CUDA's error code on its last line
_CLIENT_PROBE = """import ctypes, sys
cuda = ctypes.CDLL("libcuda.so.1")
dev, ctx = ctypes.c_int(), ctypes.c_void_p()
for name, call in (("cuInit", lambda: cuda.cuInit(0)), ("cuDeviceGet", lambda: cuda.cuDeviceGet(ctypes.byref(dev), 0)),
                   ("cuDevicePrimaryCtxRetain", lambda: cuda.cuDevicePrimaryCtxRetain(ctypes.byref(ctx), dev))):
  code = call()
  if code:
    sys.exit(f"{name}: CUDA error {code}")
cuda.cuDevicePrimaryCtxRelease(dev)
"""


def client_error(mps: "Mps", gpu: str) -> str | None:
  """Why a process on GPU `gpu` cannot run through the daemon (some hosts' sandboxes have no MPS
  server), or None where it can."""
  env = {**mps._env(), "CUDA_VISIBLE_DEVICES": gpu}  # noqa: SLF001
  try:
    done = subprocess.run([sys.executable, "-c", _CLIENT_PROBE], env=env, capture_output=True, text=True, timeout=60)
  except subprocess.TimeoutExpired:
    return "a CUDA context through it took over 60 s"
  said = (done.stderr.strip().splitlines() or ["no message"])[-1]
  return None if done.returncode == 0 else f"a CUDA context through it failed ({said[:200]})"


def start() -> Mps:
  """Starts a control daemon of its own (a fresh pipe directory); OSError with the reason where it
  cannot (no control program, or it refused to start)."""
  if shutil.which(CONTROL) is None:
    raise OSError(f"--mps on: {CONTROL} is not installed (NVIDIA's driver utilities)")
  pipe_dir = tempfile.mkdtemp(prefix="mjx-tracks-mps-")
  mps = Mps(pipe_dir, os.path.join(pipe_dir, "log"))
  os.makedirs(mps.log_dir)
  done = subprocess.run([CONTROL, "-d"], env=mps._env(), stdin=subprocess.DEVNULL, capture_output=True, text=True,  # noqa: SLF001
                        timeout=60)
  if done.returncode != 0:
    shutil.rmtree(pipe_dir, ignore_errors=True)
    raise OSError(f"{CONTROL} -d failed ({done.returncode}): {(done.stderr or done.stdout).strip()[:200]}")
  return mps

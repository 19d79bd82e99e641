"""The Dask cluster that runs studies and the server's launches.

Started here (the default), it is one worker per GPU (CUDA_VISIBLE_DEVICES pinned) with
`slots_per_gpu` run slots (more than one: under CUDA MPS, train.study.mps) and a CPU worker
(JAX_PLATFORMS=cpu) with `cpu_slots`; every endpoint (scheduler, nannies, workers) listens on
127.0.0.1 only, speaks TLS with credentials made for this cluster alone (mutual TLS: a process
without them cannot connect, not even another user of this machine), and no Dask dashboard is
started. An existing cluster (`--scheduler`) on another host must be a `tls://` address with
`--tls-ca-file`, `--tls-cert` and `--tls-key` (Dask's own TLS authentication); a loopback address is
trusted as given.
"""

from __future__ import annotations

import argparse
import atexit
import subprocess
import urllib.parse

from train.study import mps

QUIET = {"DASK_LOGGING__DISTRIBUTED": "error"}  # workers log errors only (the study prints progress)
LOOPBACK_HOST = "127.0.0.1"  # where the local cluster's endpoints listen
LOOPBACK = ("127.0.0.1", "localhost", "::1")  # host names that stay on this machine: a cluster address
# without TLS, a server without a token (train.server.auth)


def local_gpus() -> list[str]:
  """Indices of this machine's NVIDIA GPUs (none without nvidia-smi)."""
  try:
    out = subprocess.run(["nvidia-smi", "-L"], capture_output=True, text=True, timeout=30).stdout
  except (OSError, subprocess.TimeoutExpired):
    return []
  return [str(i) for i, line in enumerate(out.splitlines()) if line.startswith("GPU ")]


def add_cluster_args(p: argparse.ArgumentParser) -> None:
  """The options of the cluster a command runs on (train.study, train.server)."""
  p.add_argument("--scheduler", metavar="tls://HOST:8786",
                 help="an existing Dask cluster (its workers declare resources gpu=N and/or cpu=N: their run "
                      "slots); off this machine it must be tls:// with --tls-ca-file, --tls-cert, --tls-key")
  p.add_argument("--tls-ca-file", help="with --scheduler: the CA certificate of the cluster's TLS")
  p.add_argument("--tls-cert", help="with --scheduler: this client's certificate")
  p.add_argument("--tls-key", help="with --scheduler: this client's private key")
  p.add_argument("--gpus", help="local GPUs to use, e.g. 0,1 (default: all)")
  p.add_argument("--slots-per-gpu", type=int, default=1, help="runs at once on one GPU (default 1)")
  p.add_argument("--cpu-slots", type=int, help="runs at once on the CPU backend (default: 1 without GPUs, else 0)")
  p.add_argument("--mps", default="auto", choices=mps.MODES,
                 help="CUDA MPS for runs sharing a GPU, each kept to %d %% of its multiprocessors (default auto: "
                      "where --slots-per-gpu > 1, nvidia-cuda-mps-control is installed and a probe's CUDA context "
                      "goes through it; else a note, and the runs take turns on the GPU)" % mps.SM_SHARE)


def _nanny(slots: int, kind: str, env: dict, cls) -> dict:
  """A worker process with `slots` runs at once, resource `kind` = slots, logging errors only."""
  return {"cls": cls, "options": {"nthreads": slots, "resources": {kind: slots}, "silence_logs": 40,
                                  "env": {**env, **QUIET}}}


def worker_specs(gpus: list[str], slots_per_gpu: int, cpu_slots: int, gpu_env: dict | None = None) -> dict:
  """SpecCluster worker specs; resources `gpu` / `cpu` count run slots; gpu_env: more environment of
  the GPU workers' runs (an MPS daemon's client_env)."""
  from distributed import Nanny  # noqa: PLC0415
  # runs sharing a GPU split its memory (JAX takes 75 % of it per process by default)
  share = {"XLA_PYTHON_CLIENT_MEM_FRACTION": f"{0.9 / slots_per_gpu:.2f}"} if slots_per_gpu > 1 else {}
  env = {**share, **(gpu_env or {})}
  specs = {f"gpu{g}": _nanny(slots_per_gpu, "gpu", {"CUDA_VISIBLE_DEVICES": g, **env}, Nanny) for g in gpus}
  if cpu_slots:
    specs["cpu"] = _nanny(cpu_slots, "cpu", {"JAX_PLATFORMS": "cpu", "CUDA_VISIBLE_DEVICES": ""}, Nanny)
  return specs


def _private(security) -> dict:
  """A server's options that keep it to this machine and to holders of the cluster's credentials:
  loopback, mutual TLS, no dashboard (its HTTP port, on loopback too, serves no routes)."""
  return {"host": LOOPBACK_HOST, "protocol": "tls://", "security": security, "dashboard": False,
          "dashboard_address": f"{LOOPBACK_HOST}:0"}


def local_cluster(specs: dict):
  """A SpecCluster of the given worker processes, every endpoint private (_private) with temporary
  credentials made here; a worker's death fails its task at once (the study retries it and records
  the attempt), rather than Dask re-running it unrecorded."""
  import dask  # noqa: PLC0415
  from distributed import Scheduler, Security, SpecCluster  # noqa: PLC0415
  if not specs:
    raise ValueError("the cluster needs a GPU or a CPU slot")
  dask.config.set({"distributed.scheduler.allowed-failures": 0, "logging.distributed": "error",
                   # no HTTP routes (health, metrics, JSON info) on the scheduler's or workers' HTTP port
                   "distributed.scheduler.http.routes": [], "distributed.worker.http.routes": []})
  security = Security.temporary()  # a self-signed CA and certificate, in memory, for this cluster only
  workers = {name: {**w, "options": {**w["options"], **_private(security)}} for name, w in specs.items()}
  return SpecCluster(workers=workers, scheduler={"cls": Scheduler, "options": _private(security)},
                     security=security, silence_logs=40)


def remote_security(address: str, ca: str | None, cert: str | None, key: str | None):
  """The distributed.Security for connecting to an existing cluster; ValueError unless it is on
  loopback or a tls:// address with all three credential files."""
  from distributed import Security  # noqa: PLC0415
  parsed = urllib.parse.urlsplit(address if "://" in address else f"tcp://{address}")
  files = (ca, cert, key)
  if any(files) and not all(files):
    raise ValueError("--tls-ca-file, --tls-cert and --tls-key go together")
  if all(files):
    if parsed.scheme != "tls":
      raise ValueError(f"--scheduler {parsed.scheme}://...: TLS credentials need a tls:// address")
    return Security(tls_ca_file=ca, tls_client_cert=cert, tls_client_key=key, require_encryption=True)
  if parsed.hostname not in LOOPBACK:
    raise ValueError(f"--scheduler on {parsed.hostname}: a cluster off this machine needs tls:// and "
                     "--tls-ca-file, --tls-cert, --tls-key (Dask's TLS authentication)")
  return None


def _mps(args, gpus: list[str]) -> mps.Mps | None:
  """The daemon the GPU workers' runs go through where --mps wants one (train.study.mps), started here
  and stopped at exit; None without (auto: with a note where runs share a GPU). OSError where `--mps
  on` cannot have one."""
  mode = getattr(args, "mps", "auto")
  if not mps.wanted(mode, args.slots_per_gpu, gpus):
    return None
  try:
    daemon = mps.start()
    atexit.register(daemon.stop)  # at any exit that runs Python's exit handlers (not SIGKILL, SIGHUP)
    error = mps.client_error(daemon, gpus[0])
    if error:
      atexit.unregister(daemon.stop)
      daemon.stop()
      raise OSError(f"{mps.CONTROL}: {error}")
  except OSError as e:
    if mode == "on":
      raise
    print(f"note: no CUDA MPS ({e}); the runs sharing a GPU take turns on it", flush=True)
    return None
  print(f"CUDA MPS for {args.slots_per_gpu} runs a GPU, each at most {mps.SM_SHARE} % of its multiprocessors",
        flush=True)
  return daemon


def make_client(args):
  """(Dask client, the worker kinds it has) from the cluster options (add_cluster_args): of an
  existing cluster, or of one started here on the given GPUs (default all) and CPU slots (default 1
  without GPUs, else 0); ValueError on bad counts or an unprotected remote address."""
  from distributed import Client  # noqa: PLC0415
  if args.scheduler:
    if getattr(args, "mps", "auto") == "on":
      raise ValueError("--mps on starts MPS for the workers started here, not those of --scheduler")
    security = remote_security(args.scheduler, args.tls_ca_file, args.tls_cert, args.tls_key)
    client = Client(args.scheduler, security=security, timeout=30)
    kinds = {k for w in client.scheduler_info()["workers"].values() for k in w.get("resources", {})}
    return client, tuple(k for k in ("gpu", "cpu") if k in kinds)
  chosen = args.gpus.split(",") if args.gpus else local_gpus()
  cpu = args.cpu_slots if args.cpu_slots is not None else (0 if chosen else 1)
  if args.slots_per_gpu < 1 or cpu < 0:
    raise ValueError("--slots-per-gpu must be >= 1 and --cpu-slots >= 0")
  daemon = _mps(args, chosen)
  cluster = local_cluster(worker_specs(chosen, args.slots_per_gpu, cpu, daemon.client_env() if daemon else None))
  if daemon:
    atexit.register(cluster.close)  # exit handlers run last first: the workers end, then the daemon quits
  client = Client(cluster)
  return client, tuple(k for k, n in (("gpu", len(chosen)), ("cpu", cpu)) if n)

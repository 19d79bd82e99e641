"""The study's default Dask cluster on this machine: one worker per GPU (CUDA_VISIBLE_DEVICES
pinned) with `slots_per_gpu` run slots, and a CPU worker (JAX_PLATFORMS=cpu) with `cpu_slots`."""

from __future__ import annotations

import subprocess

QUIET = {"DASK_LOGGING__DISTRIBUTED": "error"}  # workers log errors only (the study prints progress)


def local_gpus() -> list[str]:
  """Indices of this machine's NVIDIA GPUs (none without nvidia-smi)."""
  try:
    out = subprocess.run(["nvidia-smi", "-L"], capture_output=True, text=True, timeout=30).stdout
  except (OSError, subprocess.TimeoutExpired):
    return []
  return [str(i) for i, line in enumerate(out.splitlines()) if line.startswith("GPU ")]


def _nanny(slots: int, kind: str, env: dict, cls) -> dict:
  """A worker process with `slots` runs at once, resource `kind` = slots, logging errors only."""
  return {"cls": cls, "options": {"nthreads": slots, "resources": {kind: slots}, "silence_logs": 40,
                                  "env": {**env, **QUIET}}}


def worker_specs(gpus: list[str], slots_per_gpu: int, cpu_slots: int) -> dict:
  """SpecCluster worker specs; resources `gpu` / `cpu` count run slots."""
  from distributed import Nanny  # noqa: PLC0415
  # runs sharing a GPU split its memory (JAX takes 75 % of it per process by default)
  share = {"XLA_PYTHON_CLIENT_MEM_FRACTION": f"{0.9 / slots_per_gpu:.2f}"} if slots_per_gpu > 1 else {}
  specs = {f"gpu{g}": _nanny(slots_per_gpu, "gpu", {"CUDA_VISIBLE_DEVICES": g, **share}, Nanny) for g in gpus}
  if cpu_slots:
    specs["cpu"] = _nanny(cpu_slots, "cpu", {"JAX_PLATFORMS": "cpu", "CUDA_VISIBLE_DEVICES": ""}, Nanny)
  return specs


def local_cluster(specs: dict):
  """A SpecCluster of the given worker processes; a worker's death fails its task at once (the
  study retries it and records the attempt), rather than Dask re-running it unrecorded."""
  import dask  # noqa: PLC0415
  from distributed import Scheduler, SpecCluster  # noqa: PLC0415
  if not specs:
    raise ValueError("the cluster needs a GPU or a CPU slot")
  dask.config.set({"distributed.scheduler.allowed-failures": 0, "logging.distributed": "error"})
  return SpecCluster(workers=specs, scheduler={"cls": Scheduler, "options": {"dashboard_address": ":0"}},
                     silence_logs=40)


def make_client(scheduler: str | None, gpus: str | None, slots_per_gpu: int, cpu_slots: int | None):
  """(Dask client, the worker kinds it has): of an existing cluster (its workers declare gpu / cpu
  resources), or of one started here on the given GPUs (default all) and CPU slots (default 1
  without GPUs, else 0); ValueError on bad counts."""
  from distributed import Client  # noqa: PLC0415
  if scheduler:
    client = Client(scheduler)
    kinds = {k for w in client.scheduler_info()["workers"].values() for k in w.get("resources", {})}
    return client, tuple(k for k in ("gpu", "cpu") if k in kinds)
  chosen = gpus.split(",") if gpus else local_gpus()
  cpu = cpu_slots if cpu_slots is not None else (0 if chosen else 1)
  if slots_per_gpu < 1 or cpu < 0:
    raise ValueError("--slots-per-gpu must be >= 1 and --cpu-slots >= 0")
  client = Client(local_cluster(worker_specs(chosen, slots_per_gpu, cpu)))
  return client, tuple(k for k, n in (("gpu", len(chosen)), ("cpu", cpu)) if n)

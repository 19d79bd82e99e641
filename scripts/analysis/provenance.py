"""What a result file of an analysis script says of where, when and how it was made."""

from __future__ import annotations

import datetime
import platform
import sys

import jax


def provenance() -> dict:
  """{device, date, command, jax}: the first JAX device (a CPU by its processor, an accelerator by
  its kind), the UTC time, the command line as run, the JAX version."""
  d = jax.devices()[0]
  kind = (platform.processor() or platform.machine()) if d.platform == "cpu" else d.device_kind
  return {"device": f"{d.platform.upper()} ({kind})",
          "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
          "command": "python " + " ".join(sys.argv), "jax": jax.__version__}

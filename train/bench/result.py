"""A benchmark's result file: its rows with the device, date and command that produced them."""

from __future__ import annotations

import datetime
import os
import platform
import sys

from mjx_tracks import atomic


class BenchInputError(ValueError):
  """Options a benchmark cannot run with: `python -m train.bench` reports it in one line (exit 2)."""


def default_path(name: str) -> str:
  """results/bench/NAME-<device kind>.json (spaces as -), under the current folder."""
  import jax  # noqa: PLC0415
  kind = jax.devices()[0].device_kind.replace(" ", "-").replace("/", "-")
  return os.path.join("results", "bench", f"{name}-{kind}.json")


def write_result(path: str, rows: list[dict], **fields) -> dict:
  """{device, device_kind, date, command, jax, host, **fields, rows}, written to path (atomically)."""
  import jax  # noqa: PLC0415
  result = {"device": str(jax.devices()[0]), "device_kind": jax.devices()[0].device_kind,
            "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "command": "python -m train.bench " + " ".join(sys.argv[1:]), "jax": jax.__version__,
            "host": platform.node(), **fields, "rows": rows}
  os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
  atomic.write_json(path, result)
  return result

"""Writes a benchmark's rows with the device, date and command that produced them."""

from __future__ import annotations

import datetime
import json
import platform
import sys

import jax


def write_result(path: str | None, rows: list[dict], **fields) -> dict:
  """{device, device_kind, date, command, jax, host, **fields, rows}; written to path if given."""
  result = {"device": str(jax.devices()[0]), "device_kind": jax.devices()[0].device_kind,
            "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "command": "python " + " ".join(sys.argv), "jax": jax.__version__,
            "host": platform.node(), **fields, "rows": rows}
  if path:
    with open(path, "w") as f:
      json.dump(result, f, indent=1)
  return result

"""Files replaced whole or not at all: a reader (a study's status, the dashboard, a resumed run)
never sees half a file, whatever kills the writer."""

from __future__ import annotations

import json
import os


def write_json(path: str | os.PathLike, obj, indent: int | None = 1) -> None:
  """path holds obj as JSON: written to a temporary file beside it (its own per process, so writers
  never share one), then renamed over it; the temporary file is removed if writing fails."""
  tmp = f"{os.fspath(path)}.{os.getpid()}.tmp"
  try:
    with open(tmp, "w") as f:
      json.dump(obj, f, indent=indent)
    os.replace(tmp, path)
  finally:
    if os.path.exists(tmp):
      os.remove(tmp)

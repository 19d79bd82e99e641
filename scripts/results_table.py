"""What the summarize_*.py scripts share: the header of a results folder's first log, and writing
a table (STEM.md) with its data (STEM.json)."""

from __future__ import annotations

import glob
import json
import os


def log_header(folder: str, pattern: str, lines: slice) -> str:
  """Lines (e.g. command, device and date) of the folder's first log matching pattern, or ''."""
  logs = sorted(glob.glob(os.path.join(folder, pattern)))
  return "\n".join(open(logs[0]).read().splitlines()[lines]) if logs else ""


def write_summary(folder: str, stem: str, preamble: str, table: list[str], data=None) -> None:
  """Writes STEM.md (preamble, then the table) and, given data, STEM.json; prints the table."""
  if data is not None:
    with open(os.path.join(folder, f"{stem}.json"), "w") as f:
      json.dump(data, f, indent=1)
  text = "\n".join(table) + "\n"
  with open(os.path.join(folder, f"{stem}.md"), "w") as f:
    f.write(preamble + text)
  print(text, end="")

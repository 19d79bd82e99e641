"""What a server instance serves: its database, the folder its runs live in, its token."""

from __future__ import annotations

import dataclasses
import os


@dataclasses.dataclass(frozen=True)
class Settings:
  db: str  # the experiment database (train.db)
  runs_root: str  # every file a request may read lies below this folder
  token: str | None = None  # required on every request when set

  def inside_runs(self, path: str) -> str:
    """The real path of `path` if it lies below runs_root; ValueError otherwise."""
    root = os.path.realpath(self.runs_root)
    real = os.path.realpath(path)
    if os.path.commonpath([root, real]) != root:
      raise ValueError(f"{path} is outside the runs folder")
    return real

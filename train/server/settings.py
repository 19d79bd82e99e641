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
    """The real path of `path` (links followed) if it lies below runs_root; ValueError otherwise,
    whose message names no path (it goes to clients)."""
    root = os.path.realpath(self.runs_root)
    real = os.path.realpath(path)
    if os.path.commonpath([root, real]) != root:
      raise ValueError("that file is outside the server's runs folder")
    return real

  def files_below(self, folder: str) -> list[str]:
    """Every regular file below `folder` whose real path lies inside the runs folder, links into
    it included and links out of it left out; [] if the folder itself lies outside."""
    try:
      top = self.inside_runs(folder)
    except ValueError:
      return []
    out = []
    for root, _, files in os.walk(top):  # does not enter linked folders
      for name in files:
        path = os.path.join(root, name)
        try:
          if os.path.isfile(self.inside_runs(path)):
            out.append(path)
        except ValueError:
          continue
    return sorted(out)

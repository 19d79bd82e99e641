"""mujoco.mjx prints "Failed to import warp" lines when its optional Warp backend is absent; it is
not used here (DESIGN: the JAX backend). `install()` makes the first import of mujoco.mjx, by this
package, Brax or anyone, drop those lines (and keep any other), without importing mjx (or JAX) now:
`import mjx_tracks.metrics` stays light (the database, the study tools)."""

from __future__ import annotations

import contextlib
import importlib.abc
import importlib.machinery
import io
import sys

NOISE = ("Failed to import warp", "Failed to import mujoco_warp")


class _QuietLoader(importlib.abc.Loader):
  def __init__(self, loader):
    self._loader = loader

  def create_module(self, spec):
    return self._loader.create_module(spec)

  def exec_module(self, module) -> None:
    printed = io.StringIO()
    try:
      with contextlib.redirect_stdout(printed):
        self._loader.exec_module(module)
    finally:
      for line in printed.getvalue().splitlines():
        if not line.startswith(NOISE):
          print(line, file=sys.stdout)


class _QuietFinder(importlib.abc.MetaPathFinder):
  def find_spec(self, name, path, target=None):
    if name != "mujoco.mjx":
      return None
    spec = importlib.machinery.PathFinder.find_spec(name, path)
    if spec is not None and spec.loader is not None:
      spec.loader = _QuietLoader(spec.loader)
    return spec


def install() -> None:
  """Idempotent; a no-op once mujoco.mjx is imported."""
  if "mujoco.mjx" not in sys.modules and not any(isinstance(f, _QuietFinder) for f in sys.meta_path):
    sys.meta_path.insert(0, _QuietFinder())

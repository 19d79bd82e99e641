"""The optional extras (pyproject.toml's [project.optional-dependencies]): the modules each brings,
and the one-line refusal a command gives when its extra is not installed. The env and the trainer
(mjx_tracks, scenes, train.run / evaluate / db) need none."""

from __future__ import annotations

import importlib.util
import sys

# extra -> the top-level modules it installs that our code imports
EXTRAS = {
    "studies": ("distributed", "rliable", "arch", "pandas", "matplotlib"),
    "server": ("fastapi", "uvicorn", "plotly", "distributed", "rliable"),  # it launches studies, compares runs
    "export": ("jax2onnx", "onnx", "onnxruntime"),  # train.export, train.onnx_drive
    "sb3": ("stable_baselines3", "torch"),  # train.run --library sb3
}


def missing(extra: str) -> list[str]:
  """The modules of `extra` that cannot be imported here."""
  return [m for m in EXTRAS[extra] if (sys.modules[m] is None if m in sys.modules else importlib.util.find_spec(m) is None)]


class MissingExtra(ModuleNotFoundError):
  """A package needs an optional extra that is not installed (one line: which, and how)."""


def require_extra(extra: str, what: str) -> None:
  """MissingExtra naming the extra and the install command, unless every module of it imports."""
  gone = missing(extra)
  if not gone:
    return
  message = (f"{what} needs the [{extra}] extra ({', '.join(gone)} not installed): "
             f"pip install 'mjx-tracks[{extra}]' (in a checkout: pip install -e '.[{extra}]')")
  if sys.argv[:1] == ["-m"]:  # `python -m` is locating a command of this package: say it in one line
    print(f"error: {message}", file=sys.stderr)
    raise SystemExit(2)
  raise MissingExtra(message, name=gone[0])

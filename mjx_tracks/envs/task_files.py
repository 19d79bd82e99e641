"""Where the task YAML files are and which tasks they name: no JAX, no MuJoCo, so that
`import mjx_tracks` (which registers every task with Gymnasium) and the light processes around
training (a study's stand-ins, the database's CLI) start without them."""

from __future__ import annotations

import pathlib

DEFAULTS = "defaults"  # configs/defaults.yaml: every key's default; not a task


def config_dir(package: pathlib.Path | None = None) -> pathlib.Path:
  """The task YAML files beside the mjx_tracks package that runs (`package`, default this one):
  its package data configs/ once installed, else the source checkout's configs/ (the repository's
  top level). Never another checkout's: an editable install of one tree maps the package data to
  that tree, and a second tree on PYTHONPATH must still read its own YAML."""
  package = pathlib.Path(__file__).resolve().parents[1] if package is None else package
  for folder in (package / "configs", package.parent / "configs"):
    if (folder / f"{DEFAULTS}.yaml").is_file():
      return folder
  raise FileNotFoundError(f"no {DEFAULTS}.yaml in {package / 'configs'} (installed) or {package.parent / 'configs'} "
                          "(a source checkout): the install is incomplete")


def available_tasks() -> list[str]:
  """Task names: every configs/*.yaml except defaults.yaml."""
  return sorted(p.name[:-5] for p in config_dir().iterdir()
                if p.name.endswith(".yaml") and p.name[:-5] != DEFAULTS)

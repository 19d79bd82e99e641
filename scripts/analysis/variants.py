"""What the analysis scripts that drive a group's policies under other settings share: their
`--variant "NAME:KEY=VALUE;..."` specs, the runs' one recorded config, and that config overridden."""

from __future__ import annotations

import functools

from mjx_tracks.envs.config import apply_override, from_dict
from train.core.run_record import read_run_record


def parse_variants(specs: list[str], prefix: str, reserved: str, empty_ok: bool) -> dict[str, list[str]]:
  """{name: overrides} of "NAME:KEY=VALUE;KEY=VALUE" specs, every key under `prefix` (ValueError on
  another key, a name repeated or `reserved`, or no setting where not empty_ok)."""
  out = {}
  for spec in specs:
    name, sep, sets = spec.partition(":")
    name, items = name.strip(), [x.strip() for x in sets.split(";") if x.strip()]
    if not sep or not name or name in out or name == reserved or not (items or empty_ok):
      raise ValueError(f"--variant {spec!r}: NAME:KEY=VALUE;... with a new name")
    if any(not x.startswith(prefix) for x in items):
      raise ValueError(f"--variant {spec!r}: only {prefix}KEY=VALUE (the policies' task is what they trained on)")
    out[name] = items
  return out


def configured(raw: dict, overrides: list[str]):
  """The TaskConfig of a full config mapping `raw` with KEY=VALUE overrides (ConfigError names a bad one)."""
  return from_dict(functools.reduce(apply_override, overrides, raw))


def shared_config(runs: list[str]) -> dict:
  """The runs' recorded config (ValueError where they differ but for the seed)."""
  configs = [read_run_record(r)["config"] for r in runs]
  if any(c != configs[0] for c in configs[1:]):
    raise ValueError("the runs were configured differently; give runs of one group (seeds of one config)")
  return configs[0]

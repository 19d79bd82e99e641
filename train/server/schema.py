"""The configuration schema the dashboard's form is built from: every key of the task config in
its YAML section, with its type, its default (configs/defaults.yaml, or a task's own value), its
allowed range where one is declared on the field (mjx_tracks.bounds, what validation checks) and
the comment that follows it in configs/defaults.yaml (units, choices)."""

from __future__ import annotations

import dataclasses
import re
import typing

from mjx_tracks.envs.config import DEFAULTS, TaskConfig, config_dir, load_config
from scenes.kinds import parameter_limits

LINE = re.compile(r"^(?P<indent> *)(?P<key>[A-Za-z_][A-Za-z0-9_]*):(?P<rest>[^#]*)(#\s*(?P<note>.*))?$")


def yaml_notes() -> dict[str, str]:
  """{dotted key: its comment} from configs/defaults.yaml (two-space indents; continuation
  comment lines join the key above)."""
  notes, path, last = {}, [], None
  for line in config_dir().joinpath(f"{DEFAULTS}.yaml").read_text().splitlines():
    m = LINE.match(line)
    if m:
      depth = len(m["indent"]) // 2
      path = path[:depth] + [m["key"]]
      last = ".".join(path)
      if m["note"]:
        notes[last] = m["note"].strip()
    elif line.strip().startswith("#") and last in notes and line.startswith(" " * 8):
      notes[last] += " " + line.strip().lstrip("#").strip()
  return notes


def _kind(tp) -> str:
  """A form field kind: bool | int | float | str | list."""
  if typing.get_origin(tp) is tuple:
    return "list"
  return {bool: "bool", int: "int", float: "float"}.get(tp, "str")


def _fields(cls, values, prefix: str, notes: dict) -> list[dict]:
  limits = parameter_limits()  # a scene parameter's range: its scene kind's (scenes.kinds)
  hints = typing.get_type_hints(cls)
  out = []
  for f in dataclasses.fields(cls):
    key, value = f"{prefix}{f.name}", getattr(values, f.name)
    if dataclasses.is_dataclass(hints[f.name]):
      out += _fields(hints[f.name], value, key + ".", notes)
    else:
      plain = [dataclasses.asdict(v) if dataclasses.is_dataclass(v) else v for v in value] \
          if isinstance(value, tuple) else value
      b = f.metadata.get("bound")  # mjx_tracks.bounds: the range validation checks
      out.append({"key": key, "kind": _kind(hints[f.name]), "default": plain, "note": notes.get(key, ""),
                  "range": b.text() if b else limits.get(key, "")})
  return out


def schema(task: str) -> list[dict]:
  """[{section, fields: [{key, kind, default, note, range}]}] for a task, sections in the YAML's order."""
  cfg, notes = load_config(task), yaml_notes()
  sections = []
  for f in dataclasses.fields(TaskConfig):
    value = getattr(cfg, f.name)
    if dataclasses.is_dataclass(value):
      sections.append({"section": f.name, "fields": _fields(type(value), value, f.name + ".", notes)})
    elif f.name != "task":
      sections.append({"section": f.name, "fields": [{"key": f.name, "kind": "str", "default": value,
                                                       "note": notes.get(f.name, ""), "range": ""}]})
  return sections

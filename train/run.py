"""`python -m train.run --task TASK`: the product's main job (training lands with issue 6).

Today it resolves the task's configuration (configs/TASK.yaml plus --set overrides), prints it,
and drives the task's robot through a scripted episode on the task's hardest staircase so that the
simulator stack is exercised end to end.
"""

from __future__ import annotations

import argparse
import pathlib
import sys

import yaml

CONFIG_DIR = pathlib.Path(__file__).resolve().parent.parent / "configs"


def available_tasks() -> list[str]:
  return sorted(p.stem for p in CONFIG_DIR.glob("*.yaml"))


def load_task_config(task: str, overrides: list[str]) -> dict:
  """configs/<task>.yaml with dotted KEY=VALUE overrides; unknown keys fail loudly."""
  path = CONFIG_DIR / f"{task}.yaml"
  if not path.exists():
    raise SystemExit(f"error: unknown task {task!r}; available: {', '.join(available_tasks())}")
  cfg = yaml.safe_load(path.read_text())
  for item in overrides:
    key, sep, value = item.partition("=")
    if not sep:
      raise SystemExit(f"error: --set expects KEY=VALUE, got {item!r}")
    node, parts = cfg, key.split(".")
    for part in parts[:-1]:
      if not isinstance(node.get(part), dict):
        raise SystemExit(f"error: unknown config key {key!r}")
      node = node[part]
    if parts[-1] not in node:
      raise SystemExit(f"error: unknown config key {key!r}")
    node[parts[-1]] = yaml.safe_load(value)
  return cfg


def main(argv: list[str] | None = None) -> int:
  p = argparse.ArgumentParser(prog="python -m train.run", description=__doc__.splitlines()[0])
  p.add_argument("--task", required=True, help=f"one of: {', '.join(available_tasks())}")
  p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                 help="dotted config override, e.g. --set episode.max_steps=100")
  args = p.parse_args(argv)
  cfg = load_task_config(args.task, args.set)
  print(yaml.safe_dump(cfg, sort_keys=False).rstrip())
  print("\nnote: RL training is not built yet (issue 6); running the scripted stair controller "
        "on the task's hardest staircase instead.", file=sys.stderr)
  from mjx_tracks import drive  # noqa: PLC0415  (heavy import after argument checks)
  scene = cfg["scene"]
  stairs = f"{scene['riser'][1]},{scene['tread'][0]},{scene['steps'][1]}"
  return drive.main(["--robot", str(cfg["robot"]), "--stairs", stairs,
                     "--direction", scene["direction"], "--seconds", "20"])


if __name__ == "__main__":
  sys.exit(main())

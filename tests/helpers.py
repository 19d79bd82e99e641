"""Small things several test files share."""

import json
import os

# a small task variant for training tests: no beams, short episodes (compiles and runs quickly on a CPU)
TINY = ["--set", "observation.parts=[v, flippers_paired, arm, pitch]", "--set", "episode.max_steps=8"]


def run_id(out: str) -> str:
  """The run id recorded in a run directory."""
  with open(os.path.join(out, "run.json")) as f:
    return json.load(f)["run_id"]

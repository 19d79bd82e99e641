"""Robot registry: look a robot up by number or name."""

from mjx_tracks.robots.absolem import ABSOLEM
from mjx_tracks.robots.jaguar import JAGUAR
from mjx_tracks.robots.spec import RobotSpec

ROBOTS: dict[str, RobotSpec] = {"1": JAGUAR, "jaguar": JAGUAR, "2": ABSOLEM, "absolem": ABSOLEM}


def get_robot(key: str | int) -> RobotSpec:
  """Returns the robot spec for '1' / 'jaguar' / '2' / 'absolem'."""
  k = str(key).lower()
  if k not in ROBOTS:
    raise KeyError(f"unknown robot {key!r}; known: {sorted(set(ROBOTS))}")
  return ROBOTS[k]

"""The scene parameters of every layout: the straight staircase's and each terrain kind's (scenes.terrain
lays those out): names, units, hard ends, what the generator supports and which are integers. Task
configs name their ranges by these; their default ranges are in configs/defaults.yaml."""

from __future__ import annotations

import dataclasses
import math
from typing import Callable

MAX_STEPS = 15  # the longest staircase (box pool) a task may ask for
TREAD_LIMITS, RISER_LIMITS = (0.1, 1.0), (0.01, 0.4)  # m, what the staircase generator supports


@dataclasses.dataclass(frozen=True)
class TerrainParams:
  """One kind's parameters, in xi order."""
  names: tuple[str, ...]
  hard: tuple[str, ...]  # "low" (harder when smaller) or "high"
  limits: tuple[tuple[float, float], ...]  # what the generator supports (m, or a count)
  integer: tuple[bool, ...]
  corridor: bool = True  # laid out in the 2 m corridor between side walls (else open, no walls)
  check: Callable[[tuple[float, ...]], str] = lambda xi: ""  # what is wrong with a parameter set ("": fine)
  units: tuple[str, ...] = ()  # of each parameter: "m", "rad" or "" (a count); () for all "m"

  def unit(self, name: str) -> str:
    return self.units[self.names.index(name)] if self.units else "m"

  def hardest(self, range_of: Callable[[str], tuple[float, float]]) -> list[float]:
    """Each parameter at the hard end of its (min, max) range, range_of(name)."""
    return [range_of(n)[end == "high"] for n, end in zip(self.names, self.hard)]


STAIRS = TerrainParams(("tread", "riser", "steps"), ("low", "high", "high"),  # hardest: short, tall, many
                       (TREAD_LIMITS, RISER_LIMITS, (1, MAX_STEPS)), (False, False, True), units=("m", "m", ""))
_STEP = TerrainParams(("height",), ("high",), ((0.01, 0.6),), (False,))  # m
_LANDING = TerrainParams(("tread", "riser", "steps", "landing"), ("low", "high", "high", "low"),
                         (TREAD_LIMITS, RISER_LIMITS, (3, MAX_STEPS), (0.3, 3.0)), (False, False, True, False),
                         units=("m", "m", "", "m"))
MAX_TURN = math.pi  # rad, the most a spiral turns before its landing: (steps - 1) angle


def _spiral_check(xi: tuple[float, ...]) -> str:
  """A spiral turns at most MAX_TURN before its landing (so its landing clears its first steps)."""
  radius, angle, riser, steps = xi
  return "" if (steps - 1) * angle <= MAX_TURN + 1e-9 else \
      f"(steps - 1) x angle = {(steps - 1) * angle:.3g} rad must be <= pi"


_SPIRAL = TerrainParams(("radius", "angle", "riser", "steps"), ("low", "low", "high", "high"),
                        ((1.2, 20.0), (0.05, 1.0), RISER_LIMITS, (2, MAX_STEPS)), (False, False, False, True),
                        corridor=False, check=_spiral_check, units=("m", "rad", "m", ""))
TERRAIN_PARAMS: dict[str, TerrainParams] = {
    "step_up": _STEP,
    "step_down": _STEP,
    "uplift": TerrainParams(("height", "length"), ("high", "low"), ((0.01, 0.6), (0.1, 3.0)), (False, False)),
    "rails": TerrainParams(("height", "gap"), ("high", "high"), ((0.01, 0.4), (0.2, 2.0)), (False, False)),
    "waves": TerrainParams(("amplitude", "wavelength"), ("high", "low"), ((0.01, 0.5), (0.5, 5.0)), (False, False)),
    "blocks": TerrainParams(("height", "length"), ("high", "low"), ((0.01, 0.4), (0.2, 1.0)), (False, False)),
    "landing_up": _LANDING,
    "landing_down": _LANDING,
    "spiral_up": _SPIRAL,
    "spiral_down": _SPIRAL,
}


def corridor_world(kinds: tuple[str, ...]) -> bool:
  """Whether terrain kinds stand in the corridor (else in the open, the spirals); ValueError if they
  mix the two worlds, which compile to different programs."""
  worlds = {TERRAIN_PARAMS[k].corridor for k in kinds}
  if len(worlds) > 1:
    raise ValueError(f"mixes corridor kinds with spirals (which stand in the open, without the corridor's walls): "
                     f"{list(kinds)}")
  return worlds.pop()

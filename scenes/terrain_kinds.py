"""The terrain kinds' parameters (scenes.terrain lays them out): names, hard ends, what the
generator supports and which are integers. Task configs name their ranges by these."""

from __future__ import annotations

import dataclasses

MAX_STEPS = 15  # the longest staircase (box pool) a task may ask for
TREAD_LIMITS, RISER_LIMITS = (0.1, 1.0), (0.01, 0.4)  # m, what the staircase generator supports


@dataclasses.dataclass(frozen=True)
class TerrainParams:
  """One kind's parameters, in xi order."""
  names: tuple[str, ...]
  hard: tuple[str, ...]  # "low" (harder when smaller) or "high"
  limits: tuple[tuple[float, float], ...]  # what the generator supports (m, or a count)
  integer: tuple[bool, ...]


_STEP = TerrainParams(("height",), ("high",), ((0.01, 0.6),), (False,))  # m
_LANDING = TerrainParams(("tread", "riser", "steps", "landing"), ("low", "high", "high", "low"),
                         (TREAD_LIMITS, RISER_LIMITS, (3, MAX_STEPS), (0.3, 3.0)), (False, False, True, False))
TERRAIN_PARAMS: dict[str, TerrainParams] = {
    "step_up": _STEP,
    "step_down": _STEP,
    "uplift": TerrainParams(("height", "length"), ("high", "low"), ((0.01, 0.6), (0.1, 3.0)), (False, False)),
    "rails": TerrainParams(("height", "gap"), ("high", "high"), ((0.01, 0.4), (0.2, 2.0)), (False, False)),
    "waves": TerrainParams(("amplitude", "wavelength"), ("high", "low"), ((0.01, 0.5), (0.5, 5.0)), (False, False)),
    "blocks": TerrainParams(("height", "length"), ("high", "low"), ((0.01, 0.4), (0.2, 1.0)), (False, False)),
    "landing_up": _LANDING,
    "landing_down": _LANDING,
}

"""Allowed ranges of numeric config keys, declared on their dataclass fields
(`field(metadata=bound(lo, hi))`): one fact that the config's validation checks and the
dashboard's form shows."""

from __future__ import annotations

import dataclasses


@dataclasses.dataclass(frozen=True)
class Bound:
  lo: float | None = None  # None: no lower end
  hi: float | None = None  # None: no upper end
  lo_open: bool = False  # lo itself excluded
  hi_open: bool = False  # hi itself excluded

  def contains(self, v: float) -> bool:
    above = self.lo is None or (v > self.lo if self.lo_open else v >= self.lo)
    below = self.hi is None or (v < self.hi if self.hi_open else v <= self.hi)
    return above and below

  def text(self) -> str:
    """'[1, 480]', '[0, 1)', '>= 0', '> 1'."""
    if self.hi is None:
      return f"{'>' if self.lo_open else '>='} {self.lo:g}"
    return f"{'(' if self.lo_open else '['}{self.lo:g}, {self.hi:g}{')' if self.hi_open else ']'}"


def bound(lo=None, hi=None, lo_open=False, hi_open=False) -> dict:
  """Field metadata for an allowed range."""
  return {"bound": Bound(lo, hi, lo_open, hi_open)}


def field_bound(cls, name: str) -> Bound | None:
  """The declared range of a dataclass field, if any."""
  f = next((f for f in dataclasses.fields(cls) if f.name == name), None)
  return f.metadata.get("bound") if f is not None else None


def violation(obj) -> tuple[str, str] | None:
  """(field name, what is wrong) of the first field of `obj` outside its declared range, if any."""
  for f in dataclasses.fields(obj):
    b = f.metadata.get("bound")
    value = getattr(obj, f.name)
    if b is not None and not b.contains(value):
      return f.name, f"must {'be in' if b.hi is not None else 'be'} {b.text()}, got {value}"
  return None

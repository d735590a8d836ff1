"""Checks of single scenario fields: each raises ScenarioError(field, value, allowed)."""

from __future__ import annotations

import difflib
import math
import numbers
from typing import Any

from granplate.errors import ScenarioError
from granplate.setup.scenario import Scenario


def is_number(v: Any) -> bool:
    return isinstance(v, numbers.Real) and not isinstance(v, bool)


def finite(path: str, v: Any, what: str = "must be a finite number") -> float:
    if not is_number(v) or not math.isfinite(float(v)):
        raise ScenarioError(path, v, what)
    return float(v)


def positive(path: str, v: Any) -> None:
    x = finite(path, v, "must be > 0 (a finite number)")
    if not x > 0.0:
        raise ScenarioError(path, v, "must be > 0")


def nonneg(path: str, v: Any) -> None:
    x = finite(path, v, "must be >= 0 (a finite number)")
    if not x >= 0.0:
        raise ScenarioError(path, v, "must be >= 0")


def int_at_least(path: str, v: Any, lo: int) -> None:
    if not isinstance(v, numbers.Integral) or isinstance(v, bool) or v < lo:
        raise ScenarioError(path, v, f"must be an integer >= {lo}")


#: The dimensions a scenario may have: discs in the plane, spheres in space.
DIMENSIONS: tuple[int, ...] = (2, 3)


def check_dimension(d: Any) -> None:
    """The top-level `dimension`: 2 or 3 (read first: it decides what the tables may hold)."""
    if not isinstance(d, numbers.Integral) or isinstance(d, bool) or d not in DIMENSIONS:
        raise ScenarioError("dimension", d, "must be 2 (discs in the plane, the default) or 3 (spheres in space)")


def closest_name(name: str, allowed: list[str]) -> str | None:
    """The allowed name closest to a misspelled `name` (difflib's ratio >= 0.6), or None."""
    close = difflib.get_close_matches(str(name), allowed, n=1)
    return close[0] if close else None


def string_in(path: str, v: Any, allowed: tuple[str, ...]) -> None:
    """v is one of `allowed`; a misspelled string is refused with the closest one suggested."""
    if not isinstance(v, str) or v not in allowed:
        near = closest_name(v, list(allowed)) if isinstance(v, str) else None
        hint = "" if near is None else f" (did you mean {near!r}?)"
        raise ScenarioError(path, v, "must be one of " + ", ".join(repr(a) for a in allowed) + hint)


def material_exists(path: str, name: Any, s: Scenario) -> None:
    if not isinstance(name, str) or name not in s.materials:
        raise ScenarioError(path, name, "unknown material; defined materials are: " + ", ".join(sorted(s.materials)))

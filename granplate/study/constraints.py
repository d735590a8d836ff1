"""Constraints of an optimisation: bounds on the designs' metrics (docs/studies.md).

    [constraints]
    "granular_mass" = {max = 0.02}             # kg
    "max_von_mises" = {min = 1e6, max = 5e7}   # Pa

A design is feasible when every constrained metric lies within its bounds. Each bound
gives Optuna one constraint value (its `constraints_func` convention: <= 0 feasible),
the violation relative to the bound's size, (v - max) / |max| or (min - v) / |min|
(/ 1 for a bound of 0), so that bounds of different units weigh alike in the sampler.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from typing import Any

from granplate.errors import ScenarioError

#: Keys of a bound {min = a, max = b}.
BOUND_KEYS: tuple[str, ...] = ("min", "max")


@dataclass(frozen=True)
class Bound:
    """metric within [low, high] (None: no bound on that side), in the metric's unit."""

    metric: str
    low: float | None = None
    high: float | None = None

    def text(self, unit: str = "") -> str:
        """'granular_mass <= 0.02 kg', '1e6 <= max_von_mises <= 5e7 Pa'."""
        u = f" {unit}" if unit and unit != "1" else ""
        if self.low is not None and self.high is not None:
            return f"{self.low:g} <= {self.metric} <= {self.high:g}{u}"
        if self.high is not None:
            return f"{self.metric} <= {self.high:g}{u}"
        return f"{self.metric} >= {self.low:g}{u}"


def _bound_value(where: str, v: Any) -> float:
    if isinstance(v, bool) or not isinstance(v, numbers.Real) or not math.isfinite(v):
        raise ScenarioError(where, v, "expected a finite number")
    return float(v)


def parse_constraints(table: Any, units: dict[str, str]) -> tuple[Bound, ...]:
    """The [constraints] table {metric: {min = a, max = b}} as Bounds, in file order;
    units: the metrics that may be constrained (name -> unit)."""
    if table is None:
        return ()
    if not isinstance(table, dict):
        raise ScenarioError("constraints", table, "expected a table of metric = {min = a, max = b}")
    bounds = []
    for metric, spec in table.items():
        where = f"constraints.{metric}"
        if metric not in units:
            raise ScenarioError(where, spec, "unknown metric; allowed: " + ", ".join(units))
        if not isinstance(spec, dict) or not spec:
            raise ScenarioError(where, spec, "expected {min = a}, {max = b} or {min = a, max = b}")
        for k in spec:
            if k not in BOUND_KEYS:
                raise ScenarioError(f"{where}.{k}", spec[k], "unknown key; allowed: " + ", ".join(BOUND_KEYS))
        low = _bound_value(f"{where}.min", spec["min"]) if "min" in spec else None
        high = _bound_value(f"{where}.max", spec["max"]) if "max" in spec else None
        if low is not None and high is not None and not low <= high:
            raise ScenarioError(f"{where}.max", high, f"must be >= min = {low!r}")
        bounds.append(Bound(metric, low, high))
    return tuple(bounds)


def _scale(bound: float) -> float:
    return abs(bound) if bound != 0 else 1.0


def violations(bounds: tuple[Bound, ...], summary: dict[str, Any]) -> list[float]:
    """One value per bound side (Optuna's convention: <= 0 when satisfied), relative to
    the bound; a missing or non-finite metric violates its bounds (value 1)."""
    out = []
    for b in bounds:
        v = summary.get(b.metric)
        ok = isinstance(v, numbers.Real) and not isinstance(v, bool) and math.isfinite(v)
        if b.low is not None:
            out.append((b.low - v) / _scale(b.low) if ok else 1.0)
        if b.high is not None:
            out.append((v - b.high) / _scale(b.high) if ok else 1.0)
    return out


def is_feasible(values: list[float] | tuple[float, ...] | None) -> bool | None:
    """True when every constraint value is <= 0; None without constraint values."""
    if values is None:
        return None
    return all(v <= 0.0 for v in values)

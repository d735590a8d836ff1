"""Exceptions raised by granplate.

`ScenarioError` is a user's mistake in a scenario: it names the field, the value and what
is allowed, and is raised before any computation starts. `SimulationError` is a run that
went numerically wrong; it carries the partial result computed so far.
"""

from __future__ import annotations

from typing import Any


class GranplateError(Exception):
    """Base class of all granplate errors."""


class ScenarioError(GranplateError, ValueError):
    """An invalid scenario: names the field, the value found and what is allowed."""

    def __init__(self, field: str, value: Any, allowed: str):
        self.field = field
        self.value = value
        self.allowed = allowed
        super().__init__(f"scenario field '{field}' = {value!r}: {allowed}")


class SimulationError(GranplateError, RuntimeError):
    """A run that cannot go on (NaN, energy residual, non-convergence).

    `result` holds the xarray Dataset of everything computed before the failure
    (or None when nothing was computed).
    """

    def __init__(self, message: str, result: Any = None):
        super().__init__(message)
        self.result = result


class YieldWarning(UserWarning):
    """A run's elastic (Hertz) contacts passed the onset of yield of their softer body
    (docs/model.md section 3.6): the law no longer holds there. Its own category, so that
    studies and scripts can filter it (`warnings.simplefilter("ignore", YieldWarning)`)."""

"""The plate layer's own error: an input `build_plate` cannot use.

Scenarios are refused before anything is built (`granplate.setup.validate`, with a
ScenarioError naming the scenario field); a PlateError reaches only a direct caller of
the plate layer that passed inconsistent inputs. Both come from the same checks
(`granplate.setup.plate_checks`): `plate_inputs` reports theirs as a PlateError.
"""

from __future__ import annotations

import contextlib
from typing import Any, Iterator

from granplate.errors import GranplateError, ScenarioError


class PlateError(GranplateError, ValueError):
    """Inconsistent plate inputs: names the input, the value found and what is allowed."""

    def __init__(self, name: str, value: Any, allowed: str):
        self.name = name
        self.value = value
        self.allowed = allowed
        super().__init__(f"plate input '{name}' = {value!r}: {allowed}")


@contextlib.contextmanager
def plate_inputs() -> Iterator[None]:
    """Report the setup layer's plate checks (`setup.plate_checks`, the one owner of the
    plate's ranges and topology rules) on a direct caller's inputs as a PlateError."""
    try:
        yield
    except ScenarioError as err:
        raise PlateError(err.field, err.value, err.allowed) from None

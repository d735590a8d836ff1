"""The checks every kind's rules share: the tolerance on overlaps at t = 0, the range of lengths
(LENGTH_RANGE, `length_scale`), vectors and directions, the granules' columns (kept per
thread while one scenario is validated) and the bar wave speed.
"""

from __future__ import annotations

import math
import operator
import threading
from typing import Any

import numpy as np

from granplate.errors import ScenarioError
from granplate.setup.fields import is_number
from granplate.setup.granules_file import granule_path
from granplate.setup.solid_checks import is_box
from granplate.setup.materials import Material
from granplate.setup.scenario import Solid, Granule, Plate, Scenario


#: Relative tolerance on overlaps/penetrations at t = 0 (times the smaller radius).
OVERLAP_RTOL = 1e-9
#: Every coordinate and size lies within LENGTH_RANGE x the scenario's smallest length h
#: (`length_scale`): there the spacing of doubles, 2.2e-16 |x|, stays below 2.2e-10 h,
#: under the OVERLAP_RTOL x h tolerance at t = 0, so overlaps and gaps are resolved (and
#: the k-d tree's squared distances cannot overflow).
LENGTH_RANGE = 1e6


def _vector3(path: str, v: Any, what: str) -> tuple[float, float, float]:
    """Three finite numbers, or a ScenarioError naming `path` (`what`: the vector, in words)."""
    if not isinstance(v, tuple) or len(v) != 3 or not all(is_number(c) and math.isfinite(c) for c in v):
        raise ScenarioError(path, list(v) if isinstance(v, tuple) else v, f"must be three finite numbers {what}")
    return v


def _direction(path: str, v: Any, what: str) -> tuple[float, float, float]:
    """A 3D direction: three finite numbers, not all zero (any length: normalised)."""
    _vector3(path, v, what)
    if not math.hypot(*v) > 0.0:
        raise ScenarioError(path, list(v), f"must be nonzero {what} (any length > 0: normalised)")
    return v


def _granule(s: Scenario, i: int, field: str | None = None) -> str:
    """How messages name granule i of `s` (or its field): `granules[i].field`, or the row
    and column of its granules_file (setup.granules_file.granule_path)."""
    return granule_path(s.granules_file, i, field, s.dimension)


def _floats(values: list) -> np.ndarray | None:
    """`values` as an array when every one is a Python float (else None: the checks then go
    granule by granule, as their messages need)."""
    if set(map(type, values)) != {float}:
        return None
    return np.array(values, float)


class _PerThread(threading.local):
    """What one thread's validation keeps (threads validate scenarios side by side):
    `columns`, the granules whose columns `_column` holds (a strong reference: identity
    is the key) and the columns by field, emptied when `validate` returns; `passed`, the
    scenario that passed last (a weak reference) and its materials then."""

    def __init__(self):
        self.columns: list = [None, {}]
        self.passed: list = []


_THREAD = _PerThread()


def _column(gs: tuple[Granule, ...], field: str) -> np.ndarray | None:
    """The granules' `field` as `_floats` gives it, extracted once per validation."""
    if _THREAD.columns[0] is not gs:
        _THREAD.columns[:] = [gs, {}]
    cols = _THREAD.columns[1]
    if field not in cols:
        cols[field] = _floats(list(map(operator.attrgetter(field), gs)))
    return cols[field]


def bar_wave_speed(m: Material) -> float:
    """c = sqrt(E / rho) [m/s]: the speed of elastic waves along a bar of material m."""
    return math.sqrt(m.E / m.rho)


def length_scale(s: Scenario) -> tuple[float, str]:
    """(h [m], the field it comes from): the smallest length of a resolved scenario, a
    granule radius or a plate element edge (width / nx, height / ny; a box solid's
    size / elements along each axis); its radii and plate sizes already checked to be
    positive numbers."""
    key = ("length_scale", id(s))  # once per validation of the resolved scenario
    if _THREAD.columns[0] is s.granules and key in _THREAD.columns[1]:
        return _THREAD.columns[1][key]
    found = _smallest_radius(s)
    if isinstance(s.plate, Solid) and is_box(s.plate):
        found += [(s.plate.size[k] / s.plate.elements[k], f"plate.size[{k}] / plate.elements[{k}]") for k in range(3)]
    elif isinstance(s.plate, Plate):
        found += [
            (s.plate.width / s.plate.nx, "plate.width / plate.nx"),
            (s.plate.height / s.plate.ny, "plate.height / plate.ny"),
        ]
    if not found:  # a solid of a mesh file alone: no length known before the file is read
        return math.inf, "no granule"
    if _THREAD.columns[0] is s.granules:
        _THREAD.columns[1][key] = min(found)
    return min(found)


def _smallest_radius(s: Scenario) -> list[tuple[float, str]]:
    """[(R, path)]: the granule radius that `length_scale`'s min picks, with the path
    that breaks its ties (the smallest string), or every (radius, path) pair when one is
    not a Python float."""
    r = _column(s.granules, "radius") if s.granules else None
    if r is None or not np.isfinite(r).all():
        return [(g.radius, _granule(s, i, "radius")) for i, g in enumerate(s.granules)]
    r_min = float(r.min())
    ties = np.flatnonzero(r == r_min).tolist()
    if len(ties) > 1:  # the path that sorts first: its number is all that differs (and what follows it)
        # (granule_path: `granules[i].radius`, or `FILE, row i+1, column radius`)
        after, shift = ("]", 0) if s.granules_file is None else (",", 1)
        ties = [int(min([f"{i + shift}{after}" for i in ties])[:-1]) - shift]
    return [(r_min, _granule(s, ties[0], "radius"))]

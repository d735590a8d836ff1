"""Load kinds (`load.kind`), one module each, behind one registry (docs/model.md section 5).

A kind says what the shock pushes and how hard: its peak amplitude (the loop's q0,
[N/m] on a line, [N] as a total force), the plate's or solid's edge it presses (a line
load on the plate), and which granules it pushes with what share of the amplitude
(forces per unit amplitude along x, y, z and torques about them). The time amplitude is
physics.shock.shock_amplitude, the one call every kernel makes.

Adding a kind: a module here named as the kind, with a `KIND = LoadKind(...)`, and one
entry in setup.load_checks.LOAD_RULES (its dimensions and its field rules), the one
registry: `KINDS` is read from it.
"""

from __future__ import annotations

from collections.abc import Callable
from importlib import import_module
from typing import NamedTuple

import numpy as np

from granplate.setup.load_checks import LOAD_RULES
from granplate.setup.scenario import Load, Scenario


class LoadKind(NamedTuple):
    """One load kind's contract (positions pos: (ng, 2) or (ng, 3) [m], radii r (ng,) [m])."""

    name: str
    #: the loop's peak amplitude q0 of the scenario's load ([N/m] or [N])
    amplitude: Callable[[Load], float]
    #: (y0, L) [m] of the line load on the plate's (or solid's) edge, None where it does not press one
    plate_edge: Callable[[Load], tuple[float, float] | None]
    #: (ng,) bool mask of the granules the load pushes
    loaded: Callable[[Scenario, np.ndarray, np.ndarray], np.ndarray]
    #: (ng, 3) forces [-] and (ng, 3) torques [m] per unit amplitude on the granules
    resultants: Callable[[Scenario, np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]


def load_kind(s: Scenario) -> LoadKind:
    """The kind of the scenario's load (validated: setup.load_checks)."""
    return KINDS[s.load.kind]


def amplitude(s: Scenario) -> float:
    """The loop's peak shock amplitude q0 ([N/m] on a line, [N] as a total force; 0: none)."""
    return float(load_kind(s).amplitude(s.load))


def plate_edge(s: Scenario) -> tuple[float, float] | None:
    """(y0, L) [m] of a line load on the plate's or solid's edge, else None."""
    return load_kind(s).plate_edge(s.load)


def loaded_granules(s: Scenario, pos: np.ndarray, r: np.ndarray) -> np.ndarray:
    """(ng,) mask of the granules the load pushes (pos (ng, 2 or 3) [m], r (ng,) [m])."""
    if len(r) == 0:
        return np.zeros(0, bool)
    return load_kind(s).loaded(s, np.asarray(pos, float), np.asarray(r, float))


def resultants(s: Scenario, pos: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(ng, 3) forces [-] and (ng, 3) torques [m] per unit amplitude on each granule."""
    return load_kind(s).resultants(s, np.asarray(pos, float), np.asarray(r, float))


def loaded_labels(s: Scenario) -> tuple[str, ...]:
    """Labels of the granules the load of scenario `s` (labels filled: resolved) pushes, at
    their initial centres."""
    pos = np.array([(g.x, g.y, g.z) for g in s.granules], float).reshape(-1, 3)
    r = np.array([g.radius for g in s.granules], float)
    return tuple(g.label for g, on in zip(s.granules, loaded_granules(s, pos, r)) if on)


def labelled(s: Scenario) -> np.ndarray | None:
    """The mask of load.granules' labels over the granules, None when none are named."""
    if not s.load.granules:
        return None
    named = set(s.load.granules)
    return np.array([g.label in named for g in s.granules], bool)


def _kinds() -> dict[str, LoadKind]:
    """Every kind that setup.load_checks.LOAD_RULES registers, from the module of its name
    here (model.loads.NAME's KIND): the one registry of load kinds."""
    kinds = {}
    for name in LOAD_RULES:
        kind = import_module(f"{__name__}.{name}").KIND
        if kind.name != name:
            raise ImportError(f"{__name__}.{name}.KIND is named {kind.name!r}: a load kind's module bears its name")
        kinds[name] = kind
    return kinds


KINDS: dict[str, LoadKind] = _kinds()

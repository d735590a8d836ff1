"""load.kind = "none": no shock (the granules move by their initial velocities, drives
and weight alone)."""

from __future__ import annotations

import numpy as np

from granplate.model.loads import LoadKind


def _nothing(s, pos: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return np.zeros((len(r), 3)), np.zeros((len(r), 3))


KIND = LoadKind(
    name="none",
    amplitude=lambda load: 0.0,
    plate_edge=lambda load: None,
    loaded=lambda s, pos, r: np.zeros(len(r), bool),
    resultants=_nothing,
)

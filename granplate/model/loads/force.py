"""load.kind = "force" (space): a total force F(t) = force sin(pi t / T) [N] along
load.direction, shared equally by the loaded granules (docs/model.md section 5.4):
load.granules, else those whose surface lies furthest against the direction."""

from __future__ import annotations

import numpy as np

from granplate.model.loads import LoadKind, labelled
from granplate.setup.scenario import Scenario

#: Tolerance, times the largest radius, of "furthest against the direction".
FORCE_TIE_RTOL = 1e-9


def direction(s: Scenario) -> np.ndarray:
    """The unit direction of the force (load.direction, normalised)."""
    d = np.asarray(s.load.direction, float)
    return d / np.linalg.norm(d)


def loaded(s: Scenario, pos: np.ndarray, r: np.ndarray) -> np.ndarray:
    """load.granules, or the granules of smallest s . d - R (within FORCE_TIE_RTOL R_max)."""
    named = labelled(s)
    if named is not None:
        return named
    d = direction(s)
    back = pos[:, 0] * d[0] + pos[:, 1] * d[1] + pos[:, 2] * d[2] - r
    return np.abs(back - back.min()) <= FORCE_TIE_RTOL * r.max()


def resultants(s: Scenario, pos: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """direction / n_loaded on the loaded granules, zero elsewhere; no torque."""
    forces = np.zeros((len(r), 3))
    if len(r):
        mask = loaded(s, pos, r)
        if mask.any():
            forces[mask] = direction(s) / int(mask.sum())
    return forces, np.zeros((len(r), 3))


KIND = LoadKind(
    name="force", amplitude=lambda load: load.force, plate_edge=lambda load: None, loaded=loaded, resultants=resultants
)

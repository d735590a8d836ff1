"""load.kind = "line": the paper's half-sine line load q(y, t) = q0 sin(pi t / T)
sin(pi (y - y0) / L) (docs/model.md section 5.1), on the left surface of the loaded
granules (target "granules": load.granules, else column 1, the granules whose left
surface is leftmost) or as consistent nodal forces on the plate's left edge (target
"plate"), in the plane and on a planar packing in space."""

from __future__ import annotations

import numpy as np

from granplate.model.loads import LoadKind, labelled
from granplate.physics.shock import shock_resultants
from granplate.setup.scenario import Load, Scenario

#: Tolerance, times the largest radius, of "leftmost" (column 1).
COLUMN_RTOL = 1e-9


def loaded(s: Scenario, pos: np.ndarray, r: np.ndarray) -> np.ndarray:
    """The granules the line load pushes: load.granules, or column 1; none on the plate."""
    if s.load.target != "granules":
        return np.zeros(len(r), bool)
    named = labelled(s)
    if named is not None:
        return named
    left = pos[:, 0] - r
    return np.abs(left - left.min()) <= COLUMN_RTOL * r.max()


def resultants(s: Scenario, pos: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """F_i / q0 along +x and tau_i / q0 about z of the loaded granules (physics.shock)."""
    forces, torques = np.zeros((len(r), 3)), np.zeros((len(r), 3))
    if len(r):
        forces[:, 0], torques[:, 2] = shock_resultants(pos[:, 1], r, loaded(s, pos, r), s.load.y0, s.load.length)
    return forces, torques


def plate_edge(load: Load) -> tuple[float, float] | None:
    """(y0, L) [m] on the plate's left edge (target "plate"), else None."""
    return (load.y0, load.length) if load.target == "plate" else None


KIND = LoadKind(
    name="line", amplitude=lambda load: load.q0, plate_edge=plate_edge, loaded=loaded, resultants=resultants
)

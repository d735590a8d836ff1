"""The granules against a solid given by a mesh file, at t = 0: the signed distance of
each centre to the body's surface (`surface.closest_point`: the boundary's quadratic
faces, positive outside), refused by the rule of `setup.solid_checks.check_solid_clearance`
(a granule may touch the solid, not cross it; no centre inside). A box solid is checked
in closed form by `setup.validate`; a mesh file needs its surface, read here."""

from __future__ import annotations

import numpy as np
from skfem import Mesh

from granplate.setup.scenario import Scenario
from granplate.setup.solid_checks import check_solid_clearance
from granplate.solid.fe import vector_basis
from granplate.solid.surface import boundary_surface, closest_point


def surface_distances(mesh: Mesh, element: str, centres: np.ndarray) -> np.ndarray:
    """(n,) the signed distance [m] of each centre (n, 3) [m] to the surface of the body
    meshed by `mesh` with `element` (positive outside)."""
    surface = boundary_surface(vector_basis(mesh, element))
    return np.array([closest_point(surface, c).distance for c in np.asarray(centres, float).reshape(-1, 3)])


def check_clearance(s: Scenario, mesh: Mesh, named: dict[int, str], rtol: float) -> None:
    """ScenarioError naming the first granule of the resolved `s` that crosses the surface
    of its solid (meshed by `mesh`) by more than rtol x its radius, or whose centre lies
    inside it."""
    centres = np.array([(g.x, g.y, g.z) for g in s.granules], float).reshape(-1, 3)
    check_solid_clearance(s, surface_distances(mesh, s.plate.element, centres), named, rtol)

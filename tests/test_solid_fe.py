"""The solid's elements: the NumPy assembly equals scikit-fem's linear_elasticity and
vector mass forms; the mass integrates to the body's mass; rigid motions cost no energy."""

from __future__ import annotations

import numpy as np
import pytest

from granplate.solid.fe import (
    mass_matrix,
    node_coordinates,
    reference_mass,
    reference_stiffness,
    scalar_basis,
    stiffness_matrix,
    vector_basis,
)
from granplate.solid.mesh import box_mesh
from granplate.solid.modes import rigid_body_modes

E, NU, RHO = 200e9, 0.3, 7850.0


@pytest.mark.parametrize("element", ["hex20", "hex27", "tet10"])
def test_assembly_matches_scikit_fem(element):
    """K and M equal scikit-fem's forms on its vector basis (to rounding)."""
    mesh = box_mesh([0.03, 0.02, 0.01], [2, 1, 1], tetrahedra=element == "tet10")
    s, v = scalar_basis(mesh, element), vector_basis(mesh, element)
    K, M = stiffness_matrix(s, E, NU), mass_matrix(s, RHO)
    assert abs(K - reference_stiffness(v, E, NU)).max() < 1e-13 * abs(K).max()
    assert abs(M - reference_mass(v, RHO)).max() < 1e-13 * abs(M).max()
    assert np.allclose(node_coordinates(s), v.doflocs[:, 0::3].T)


@pytest.mark.parametrize("element", ["hex20", "hex27", "tet10"])
def test_mass_and_rigid_motions(element):
    """A translation's kinetic mass is rho V; K annihilates the six rigid-body motions."""
    mesh = box_mesh([0.03, 0.02, 0.01], [2, 2, 1], tetrahedra=element == "tet10")
    s = scalar_basis(mesh, element)
    K, M = stiffness_matrix(s, E, NU), mass_matrix(s, RHO)
    R = rigid_body_modes(node_coordinates(s))
    assert R[:, 0] @ (M @ R[:, 0]) == pytest.approx(RHO * 0.03 * 0.02 * 0.01, rel=1e-12)
    assert np.abs(K @ R).max() < 1e-9 * abs(K).max() * 0.03

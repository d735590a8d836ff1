"""The solid's factorisation: the nested-dissection order is a permutation whose first
separator is the plane of element faces at the median (the smaller side's dofs), and its
SuperLU factors solve K x = f to round-off."""

from __future__ import annotations

import numpy as np
import scipy.sparse.linalg as spla

from granplate.solid.boundary import fixed_dofs, free_dofs, reduced
from granplate.solid.factor import factorised, nested_dissection
from granplate.solid.fe import node_coordinates, scalar_basis, stiffness_matrix
from granplate.solid.mesh import box_mesh


def bar(elements=(4, 1, 1), clamped=()):
    mesh = box_mesh([0.01 * elements[0], 0.01, 0.01], list(elements))
    s = scalar_basis(mesh, "hex20")
    dofs = free_dofs(3 * s.N, fixed_dofs(s, mesh, clamped, ()))
    K = reduced(stiffness_matrix(s, 200e9, 0.3), dofs)
    return K, node_coordinates(s)[dofs // 3]


def test_the_first_separator_is_the_mid_plane_of_element_faces():
    """A bar of four hex20 cubes: the order is a permutation of the dofs and its last block
    (the first split's separator) is exactly the dofs on the face plane x = 2 cm, which
    alone cut the bar in two (not the element beside it)."""
    K, xyz = bar()
    order = nested_dissection(K, xyz)
    assert np.array_equal(np.sort(order), np.arange(K.shape[0]))
    plane = np.flatnonzero(np.abs(xyz[:, 0] - 0.02) < 1e-12)
    assert len(plane) == 24  # 8 nodes of a hex20 face, 3 dofs each
    assert set(order[-len(plane) :]) == set(plane)


def test_the_factors_solve_the_stiffness_system():
    """factorised(K) solves K x = f (a clamped bar of 6 x 2 x 1 hex20, three load cases)
    as SciPy's own sparse solver does, to round-off."""
    K, xyz = bar((6, 2, 1), clamped=("xmin",))
    f = np.random.default_rng(11).standard_normal((K.shape[0], 3))
    x = factorised(K, xyz)(f)
    assert np.abs(K @ x - f).max() < 1e-10 * np.abs(f).max()
    assert np.allclose(x, spla.spsolve(K.tocsc(), f), rtol=1e-9, atol=1e-9 * np.abs(x).max())

"""Plane-stress Q8 finite elements of the plate: mesh, basis, K and M, nodes (docs/model.md section 4).

The plate occupies x in [x0, x0 + width], y in [y0, y0 + height] and is meshed with
8-node serendipity quadrilaterals (scikit-fem `ElementVector(ElementQuadS2())` on
`MeshQuad.init_tensor`), plane stress, consistent mass, no damping. Every array here
is in SI units: metres, kilograms, seconds, newtons, pascals. Node n has dofs 2n (x) and
2n + 1 (y); nodes are the mesh corners followed by the edge midpoints (scikit-fem's dof
numbering).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from skfem import Basis, BilinearForm, ElementQuadS2, ElementVector, MeshQuad, asm

from granplate.plate.stress import INTORDER, voigt_strain


def plate_mesh(x0: float, y0: float, width: float, height: float, nx: int, ny: int) -> MeshQuad:
    """Structured quadrilateral mesh of [x0, x0 + width] x [y0, y0 + height] [m]."""
    return MeshQuad.init_tensor(np.linspace(x0, x0 + width, nx + 1), np.linspace(y0, y0 + height, ny + 1))


def q8_basis(mesh: MeshQuad, intorder: int = INTORDER) -> Basis:
    """Vector Q8 (serendipity) basis with intorder Gauss integration (4: 3 x 3 points)."""
    return Basis(mesh, ElementVector(ElementQuadS2()), intorder=intorder)


def assemble_stiffness(basis: Basis, D: np.ndarray, thickness: float) -> sp.csr_matrix:
    """K = thickness * int eps(v) . D eps(u) dA [N/m], symmetrised exactly."""

    @BilinearForm
    def stiffness(u, v, w):
        eu = voigt_strain(u.grad)
        ev = voigt_strain(v.grad)
        return thickness * sum(ev[a] * D[a, b] * eu[b] for a in range(3) for b in range(3) if D[a, b] != 0.0)

    K = asm(stiffness, basis).tocsr()
    return ((K + K.T) * 0.5).tocsr()


def assemble_mass(basis: Basis, rho: float, thickness: float) -> sp.csr_matrix:
    """Consistent mass M = rho * thickness * int u . v dA [kg], symmetrised exactly."""

    @BilinearForm
    def mass(u, v, w):
        return rho * thickness * (u[0] * v[0] + u[1] * v[1])

    M = asm(mass, basis).tocsr()
    return ((M + M.T) * 0.5).tocsr()


def node_coordinates(basis: Basis) -> np.ndarray:
    """(n_nodes, 2) coordinates [m] of the Q8 nodes, node n owning dofs 2n (x), 2n + 1 (y)."""
    nodal, facet = basis.nodal_dofs, basis.facet_dofs
    n_vertices = nodal.shape[1]
    # scikit-fem numbers the vector dofs node by node, x first: check rather than assume.
    expected_nodal = 2 * np.arange(n_vertices)
    expected_facet = 2 * (n_vertices + np.arange(facet.shape[1]))
    if not (
        np.array_equal(nodal[0], expected_nodal)
        and np.array_equal(nodal[1], expected_nodal + 1)
        and np.array_equal(facet[0], expected_facet)
        and np.array_equal(facet[1], expected_facet + 1)
        and basis.N == 2 * (n_vertices + facet.shape[1])
    ):
        raise RuntimeError("unexpected scikit-fem dof numbering for ElementVector(ElementQuadS2())")

    return np.ascontiguousarray(basis.doflocs[:, ::2].T)


def vtk_elements(mesh: MeshQuad) -> np.ndarray:
    """(n_elem, 8) node indices in VTK_QUADRATIC_QUAD order, corners anticlockwise.

    Corners are mesh vertices; the midside node of facet f is node n_vertices + f.
    scikit-fem's facet i of an element joins its corners i and i + 1.
    """
    t = mesh.t.T  # (n_elem, 4)
    mid = mesh.t2f.T + mesh.p.shape[1]  # midside of edge (i, i+1)
    xy = mesh.p.T[t]  # (n_elem, 4, 2)
    x, y = xy[..., 0], xy[..., 1]
    signed_area = 0.5 * np.sum(x * np.roll(y, -1, axis=1) - np.roll(x, -1, axis=1) * y, axis=1)
    corners = t.copy()
    mids = mid.copy()
    cw = signed_area < 0
    # Reverse a clockwise element: corners (0, 3, 2, 1), edges (0-3, 3-2, 2-1, 1-0).
    corners[cw] = t[cw][:, [0, 3, 2, 1]]
    mids[cw] = mid[cw][:, [3, 2, 1, 0]]
    return np.hstack([corners, mids]).astype(np.int64)

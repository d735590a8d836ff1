"""The solid's finite elements: quadratic Lagrange elements (scikit-fem), isotropic
linear elasticity K and the consistent mass M.

Elements (`ELEMENTS`): "hex20" (ElementHexS2, 20-node serendipity), "hex27" (ElementHex2,
27-node triquadratic), "tet10" (ElementTetP2, 10-node). Each node n of the vector basis
has the dofs 3n (x), 3n + 1 (y), 3n + 2 (z).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from skfem import Basis, BilinearForm, ElementHex2, ElementHexS2, ElementTetP2, ElementVector, Mesh, MeshHex, asm
from skfem.helpers import dot
from skfem.models.elasticity import lame_parameters, linear_elasticity

#: The element names and their scikit-fem elements.
ELEMENTS: dict[str, type] = {"hex20": ElementHexS2, "hex27": ElementHex2, "tet10": ElementTetP2}
#: Gauss order of the element integrals (exact for the quadratic elements' mass matrix).
INTORDER = 4


def is_hexahedral(element: str) -> bool:
    """Whether the element lives on a hexahedral mesh."""
    return element.startswith("hex")


def vector_basis(mesh: Mesh, element: str) -> Basis:
    """The 3-component vector basis of an element name on a mesh of its cell type."""
    if is_hexahedral(element) != isinstance(mesh, MeshHex):
        raise ValueError(f"element {element!r} needs a {'hexahedral' if is_hexahedral(element) else 'tetrahedral'} mesh")
    return Basis(mesh, ElementVector(ELEMENTS[element]()), intorder=INTORDER)


def node_coordinates(basis: Basis) -> np.ndarray:
    """(n_nodes, 3) coordinates [m] of the basis' nodes (corners and mid-nodes)."""
    return np.ascontiguousarray(basis.doflocs[:, 0::3].T)


def stiffness_matrix(basis: Basis, E: float, nu: float) -> sp.csr_matrix:
    """K [N/m] of isotropic linear elasticity, sigma = lambda tr(eps) I + 2 mu eps."""
    return asm(linear_elasticity(*lame_parameters(E, nu)), basis).tocsr()


@BilinearForm
def _unit_mass(u, v, w):
    return dot(u, v)


def mass_matrix(basis: Basis, rho: float) -> sp.csr_matrix:
    """Consistent mass M [kg]: the integral of rho u . v."""
    return (rho * asm(_unit_mass, basis)).tocsr()

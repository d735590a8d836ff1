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


def _check_cells(mesh: Mesh, element: str) -> None:
    if is_hexahedral(element) != isinstance(mesh, MeshHex):
        raise ValueError(
            f"element {element!r} needs a {'hexahedral' if is_hexahedral(element) else 'tetrahedral'} mesh"
        )


def vector_basis(mesh: Mesh, element: str) -> Basis:
    """The 3-component vector basis of an element name on a mesh of its cell type."""
    _check_cells(mesh, element)
    return Basis(mesh, ElementVector(ELEMENTS[element]()), intorder=INTORDER)


def scalar_basis(mesh: Mesh, element: str) -> Basis:
    """The scalar basis of the element: node n of the vector basis has the dofs 3n + c."""
    _check_cells(mesh, element)
    return Basis(mesh, ELEMENTS[element](), intorder=INTORDER)


def node_coordinates(sbasis: Basis) -> np.ndarray:
    """(n_nodes, 3) coordinates [m] of a scalar basis' nodes (corners and mid-nodes)."""
    return np.ascontiguousarray(sbasis.doflocs.T)


def _vector_dofs(sbasis: Basis) -> np.ndarray:
    """(n_elem, n_local, 3) vector dofs 3 a + c of each element's scalar dofs a."""
    return 3 * sbasis.element_dofs.T[:, :, None] + np.arange(3)


def _scatter(Ke: np.ndarray, dofs: np.ndarray, n: int) -> sp.csr_matrix:
    """Sum element matrices Ke (n_elem, m, m) on the dofs (n_elem, m) into an (n, n) matrix."""
    rows = np.broadcast_to(dofs[:, :, None], Ke.shape).ravel()
    cols = np.broadcast_to(dofs[:, None, :], Ke.shape).ravel()
    return sp.coo_matrix((Ke.ravel(), (rows, cols)), shape=(n, n)).tocsr()


def stiffness_matrix(sbasis: Basis, E: float, nu: float) -> sp.csr_matrix:
    """K [N/m] of isotropic linear elasticity, sigma = lambda tr(eps) I + 2 mu eps, on the
    vector dofs of a scalar basis: K[(a,i),(b,j)] = integral of lambda dN_a/dx_i dN_b/dx_j
    + mu (delta_ij grad N_a . grad N_b + dN_a/dx_j dN_b/dx_i) (the same matrix as
    scikit-fem's linear_elasticity form, assembled element-wise in NumPy, faster)."""
    lam, mu = lame_parameters(E, nu)
    grad = np.stack([np.asarray(sbasis.basis[a][0].grad) for a in range(sbasis.Nbfun)])  # (m, 3, e, q)
    A = np.einsum("aieq,bjeq,eq->eabij", grad, grad, np.asarray(sbasis.dx), optimize=True)
    trace = np.einsum("eabkk->eab", A)
    Ke = lam * A + mu * (np.einsum("eab,ij->eabij", trace, np.eye(3)) + A.transpose(0, 1, 2, 4, 3))
    n_elem, m = A.shape[:2]
    Ke = Ke.transpose(0, 1, 3, 2, 4).reshape(n_elem, 3 * m, 3 * m)
    return _scatter(Ke, _vector_dofs(sbasis).reshape(n_elem, 3 * m), 3 * sbasis.N)


def mass_matrix(sbasis: Basis, rho: float) -> sp.csr_matrix:
    """Consistent mass M [kg], the integral of rho u . v, on the vector dofs of a scalar
    basis (each component's scalar mass matrix)."""
    val = np.stack([np.asarray(sbasis.basis[a][0].value) for a in range(sbasis.Nbfun)])  # (m, e, q)
    Me = rho * np.einsum("aeq,beq,eq->eab", val, val, np.asarray(sbasis.dx), optimize=True)
    n_elem, m = Me.shape[:2]
    Ke = np.einsum("eab,ij->eaibj", Me, np.eye(3)).reshape(n_elem, 3 * m, 3 * m)
    return _scatter(Ke, _vector_dofs(sbasis).reshape(n_elem, 3 * m), 3 * sbasis.N)


def reference_stiffness(basis: Basis, E: float, nu: float) -> sp.csr_matrix:
    """K from scikit-fem's linear_elasticity form on the vector basis (the reference the
    NumPy assembly is tested against)."""
    return asm(linear_elasticity(*lame_parameters(E, nu)), basis).tocsr()


@BilinearForm
def _unit_mass(u, v, w):
    return dot(u, v)


def reference_mass(basis: Basis, rho: float) -> sp.csr_matrix:
    """M from scikit-fem's vector mass form on the vector basis (reference)."""
    return (rho * asm(_unit_mass, basis)).tocsr()

"""The elastic plate: plane-stress Q8 finite elements, rigid layers, modes (MODEL.md section 4).

The plate occupies x in [x0, x0 + width], y in [y0, y0 + height] and is meshed with
8-node serendipity quadrilaterals (scikit-fem `ElementVector(ElementQuadS2())` on
`MeshQuad.init_tensor`), plane stress, consistent mass, no damping. Every array here
is in SI units: metres, kilograms, seconds, newtons, pascals.

Data flows one way::

    Plate, Material -> mesh, basis -> K, M (full)            assemble_stiffness, assemble_mass
                    -> T (clamps + rigid layers)             clamped_dofs, rigid_layer_map
                    -> K_r = T^T K T, M_r = T^T M T -> Phi, omega   modal_basis
                    -> strain_op, edge_load_full                    strain_operator, edge_load_vector

A full displacement vector is x_full = T @ x_red with x_red = Phi @ q, q the modal
coordinates; node n has dofs 2n (x) and 2n + 1 (y); nodes are the mesh corners
followed by the edge midpoints (scikit-fem's dof numbering).

The expensive part of `build_plate` (assembly and the dense generalized eigenproblem)
is cached in an ``.npz`` file under ``$GRANPLATE_CACHE`` (default ``~/.cache/granplate``),
keyed by a sha256 of every input.
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import tempfile
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Sequence

import numpy as np
import scipy.linalg
import scipy.sparse as sp
import skfem
from skfem import Basis, BilinearForm, ElementQuadS2, ElementVector, FacetBasis, LinearForm, MeshQuad, asm

from granplate.errors import ScenarioError
from granplate.setup.materials import LIBRARY, Material

if TYPE_CHECKING:  # pragma: no cover
    from granplate.setup.scenario import Plate

#: Bump when anything that changes the cached arrays changes (formulas, ordering, dtypes).
CACHE_VERSION = 2

#: Gauss order for K, M and stress recovery: 3 x 3 = 9 points per element.
INTORDER = 4

#: Gauss-Legendre points per (piece of) edge facet for the consistent edge load.
EDGE_LOAD_POINTS = 8

#: Relative tolerance (times the plate height / width) for "a node lies at this coordinate".
GEOMETRY_RTOL = 1e-9

EDGES = ("top", "bottom", "left", "right")

_CACHED_ARRAYS = (
    "Phi",
    "omega",
    "strain_op_data",
    "strain_op_indices",
    "strain_op_indptr",
    "strain_op_shape",
    "edge_load_full",
    "edge_load_modal",
)


# --------------------------------------------------------------------------------------
# The model
# --------------------------------------------------------------------------------------
@dataclass(frozen=True)
class PlateModel:
    """A built plate: mesh, reduction, modes and output operators.

    Shapes: n_nodes Q8 nodes, n_full = 2 n_nodes dofs, n_red reduced dofs (clamped dofs
    removed, rigid-layer nodes slaved), n_modes kept modes, n_elem elements, n_qp = 9
    Gauss points per element, n_contacts rigid layers.

    Attributes
    ----------
    mesh, basis: the scikit-fem mesh and full (unconstrained) vector Q8 basis.
    node_xy: (n_nodes, 2) node coordinates [m]; node n has dofs 2n (x), 2n + 1 (y).
    elements: (n_elem, 8) node indices in VTK_QUADRATIC_QUAD order (4 corners
        anticlockwise, then the midsides of edges 0-1, 1-2, 2-3, 3-0).
    T: (n_full, n_red) sparse 0/1 map x_full = T @ x_red.
    Phi: (n_red, n_modes) mass-normalised modes, Phi^T M_r Phi = I [kg^-1/2].
    omega: (n_modes,) angular frequencies [rad/s], ascending.
    drive_dofs: (n_contacts, 2) reduced indices of each contact's driving x and y dofs.
    phi_drive: (2 n_contacts, n_modes) = Phi[drive_dofs.ravel()].
    edge_load_modal: (n_modes,) Phi^T T^T edge_load_full [N / kg^1/2 per N/m of q0].
    edge_load_full: (n_full,) consistent nodal forces [N] of the left-edge line load
        q(y) = sin(pi (y - y0_load) / L) for q0 = 1 N/m (zeros when none was asked).
    strain_op: (3 n_elem n_qp, n_full) sparse; rows [component][element][qp] give
        eps_xx, eps_yy, gamma_xy (engineering shear) [-] from x_full [m].
    qp_xy: (n_elem, n_qp, 2) Gauss point coordinates [m].
    D: (3, 3) plane-stress constitutive matrix [Pa].
    symmetry_nodes: node indices on y = y0 + height / 2, sorted by x.
    contact_y: (n_contacts,) contact heights as given [m].
    thickness [m], rho [kg/m^3], E [Pa], nu [-].
    """

    mesh: MeshQuad
    basis: Basis
    node_xy: np.ndarray
    elements: np.ndarray
    T: sp.csr_matrix
    Phi: np.ndarray
    omega: np.ndarray
    drive_dofs: np.ndarray
    phi_drive: np.ndarray
    edge_load_modal: np.ndarray
    edge_load_full: np.ndarray
    strain_op: sp.csr_matrix
    qp_xy: np.ndarray
    D: np.ndarray
    symmetry_nodes: np.ndarray
    contact_y: np.ndarray
    thickness: float
    rho: float
    E: float
    nu: float

    # ---- sizes -------------------------------------------------------------------
    @property
    def n_full(self) -> int:
        """Number of unconstrained dofs (2 per node)."""
        return self.T.shape[0]

    @property
    def n_red(self) -> int:
        """Number of reduced dofs."""
        return self.T.shape[1]

    @property
    def n_modes(self) -> int:
        """Number of kept modes."""
        return self.omega.shape[0]

    @property
    def n_qp(self) -> int:
        """Gauss points per element."""
        return self.qp_xy.shape[1]

    # ---- matrices on demand (not cached: cheap to assemble) -------------------------
    def stiffness_matrix(self) -> sp.csr_matrix:
        """Full (unconstrained) stiffness K [N/m], (n_full, n_full)."""
        return assemble_stiffness(self.basis, self.D, self.thickness)

    def mass_matrix(self) -> sp.csr_matrix:
        """Full (unconstrained) consistent mass M [kg], (n_full, n_full)."""
        return assemble_mass(self.basis, self.rho, self.thickness)

    # ---- fields from modal coordinates --------------------------------------------
    def full_dofs(self, q: np.ndarray) -> np.ndarray:
        """x_full = T Phi q [m]: (..., n_modes) -> (..., n_full)."""
        q = np.asarray(q, dtype=float)
        flat = q.reshape(-1, self.n_modes)
        x_full = (self.T @ (self.Phi @ flat.T)).T
        return x_full.reshape(q.shape[:-1] + (self.n_full,))

    def full_displacement(self, q: np.ndarray) -> np.ndarray:
        """Nodal displacements [m]: q (..., n_modes) -> (..., n_nodes, 2)."""
        x_full = self.full_dofs(q)
        return x_full.reshape(x_full.shape[:-1] + (-1, 2))

    def strains(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """eps_xx, eps_yy, gamma_xy [-] at the Gauss points, each (..., n_elem, n_qp)."""
        x_full = self.full_dofs(q)
        flat = x_full.reshape(-1, self.n_full)
        eps = (self.strain_op @ flat.T).T  # (batch, 3 n_elem n_qp)
        n_elem = self.qp_xy.shape[0]
        eps = eps.reshape(x_full.shape[:-1] + (3, n_elem, self.n_qp))
        return eps[..., 0, :, :], eps[..., 1, :, :], eps[..., 2, :, :]

    def stresses(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """sigma_xx, sigma_yy, tau_xy [Pa] at the Gauss points, each (..., n_elem, n_qp)."""
        exx, eyy, gxy = self.strains(q)
        D = self.D
        sxx = D[0, 0] * exx + D[0, 1] * eyy + D[0, 2] * gxy
        syy = D[1, 0] * exx + D[1, 1] * eyy + D[1, 2] * gxy
        sxy = D[2, 0] * exx + D[2, 1] * eyy + D[2, 2] * gxy
        return sxx, syy, sxy

    def von_mises(self, q: np.ndarray) -> np.ndarray:
        """Plane-stress von Mises stress [Pa] (MODEL.md eq. 12) at the Gauss points.

        sqrt(sxx^2 - sxx syy + syy^2 + 3 sxy^2), shape (..., n_elem, n_qp).
        """
        sxx, syy, sxy = self.stresses(q)
        return von_mises_plane_stress(sxx, syy, sxy)

    def energy(self, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        """Plate energy [J]: 1/2 qdot.qdot + 1/2 sum omega^2 q^2 (= 1/2 v^T M v + 1/2 x^T K x)."""
        q = np.asarray(q, dtype=float)
        qdot = np.asarray(qdot, dtype=float)
        return 0.5 * np.sum(qdot**2, axis=-1) + 0.5 * np.sum(self.omega**2 * q**2, axis=-1)

    def compliance(self, dt: float) -> np.ndarray:
        """Driving-dof block of (M_r + dt^2 K_r / 4)^-1 [1/kg] (paper eq. 8), (2 nc, 2 nc).

        = phi_drive diag(1 / (1 + dt^2 omega^2 / 4)) phi_drive^T; rows/columns ordered
        [k0x, k0y, k1x, k1y, ...]. With all modes kept this is exact; with fewer it is
        the truncated modal approximation.
        """
        weights = 1.0 / (1.0 + 0.25 * dt**2 * self.omega**2)
        return (self.phi_drive * weights) @ self.phi_drive.T


# --------------------------------------------------------------------------------------
# Constitutive law and assembly
# --------------------------------------------------------------------------------------
def plane_stress_matrix(E: float, nu: float) -> np.ndarray:
    """D = E / (1 - nu^2) [[1, nu, 0], [nu, 1, 0], [0, 0, (1 - nu) / 2]] [Pa].

    Acts on (eps_xx, eps_yy, gamma_xy) with gamma_xy the engineering shear strain.
    """
    return E / (1.0 - nu**2) * np.array(
        [[1.0, nu, 0.0], [nu, 1.0, 0.0], [0.0, 0.0, 0.5 * (1.0 - nu)]]
    )


def von_mises_plane_stress(sxx: np.ndarray, syy: np.ndarray, sxy: np.ndarray) -> np.ndarray:
    """sqrt(sxx^2 - sxx syy + syy^2 + 3 sxy^2) [Pa] (plane stress, szz = 0)."""
    return np.sqrt(np.maximum(sxx**2 - sxx * syy + syy**2 + 3.0 * sxy**2, 0.0))


def _voigt_strain(grad: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(eps_xx, eps_yy, gamma_xy) from a displacement gradient grad[i, j] = du_i/dx_j."""
    return grad[0, 0], grad[1, 1], grad[0, 1] + grad[1, 0]


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
        eu = _voigt_strain(u.grad)
        ev = _voigt_strain(v.grad)
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


def strain_operator(basis: Basis) -> sp.csr_matrix:
    """Sparse map from the full dof vector to (eps_xx, eps_yy, gamma_xy) at the Gauss points.

    Shape (3 n_elem n_qp, n_full); row = component * n_elem * n_qp + element * n_qp + qp.
    """
    n_elem, n_qp = basis.dx.shape
    n_local = basis.element_dofs.shape[0]
    data = np.empty((3, n_local, n_elem, n_qp))
    cols = np.empty((n_local, n_elem, n_qp), dtype=np.int64)
    for i in range(n_local):
        exx, eyy, gxy = _voigt_strain(basis.basis[i][0].grad)
        data[0, i], data[1, i], data[2, i] = exx, eyy, gxy
        cols[i] = basis.element_dofs[i][:, None]
    rows = (
        np.arange(3)[:, None, None, None] * (n_elem * n_qp)
        + np.arange(n_elem)[None, None, :, None] * n_qp
        + np.arange(n_qp)[None, None, None, :]
    )
    rows = np.broadcast_to(rows, data.shape)
    cols3 = np.broadcast_to(cols, data.shape)
    keep = data != 0.0
    op = sp.coo_matrix(
        (data[keep], (rows[keep], cols3[keep])), shape=(3 * n_elem * n_qp, basis.N)
    ).tocsr()
    op.sum_duplicates()
    op.sort_indices()
    return op


def quadrature_points(basis: Basis) -> np.ndarray:
    """Gauss point coordinates [m], (n_elem, n_qp, 2)."""
    return np.moveaxis(np.asarray(basis.mapping.F(basis.X)), 0, -1)


# --------------------------------------------------------------------------------------
# Nodes and elements
# --------------------------------------------------------------------------------------
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


def nodes_on_line(node_xy: np.ndarray, axis: int, value: float, tol: float) -> np.ndarray:
    """Indices of the nodes whose coordinate `axis` (0: x, 1: y) is value +- tol."""
    return np.flatnonzero(np.abs(node_xy[:, axis] - value) <= tol)


def edge_nodes(node_xy: np.ndarray, plate: "Plate", x0: float) -> dict[str, np.ndarray]:
    """Node indices on each of the four plate edges ("top", "bottom", "left", "right")."""
    tx, ty = GEOMETRY_RTOL * plate.width, GEOMETRY_RTOL * plate.height
    return {
        "left": nodes_on_line(node_xy, 0, x0, tx),
        "right": nodes_on_line(node_xy, 0, x0 + plate.width, tx),
        "bottom": nodes_on_line(node_xy, 1, plate.y0, ty),
        "top": nodes_on_line(node_xy, 1, plate.y0 + plate.height, ty),
    }


def clamped_dofs(node_xy: np.ndarray, plate: "Plate", x0: float) -> np.ndarray:
    """Sorted full-dof indices fixed by plate.clamped_edges (both dofs of every edge node)."""
    unknown = [e for e in plate.clamped_edges if e not in EDGES]
    if unknown:
        raise ScenarioError(
            "plate.clamped_edges", plate.clamped_edges, f"allowed: a subset of {EDGES}; unknown {unknown}"
        )
    edges = edge_nodes(node_xy, plate, x0)
    nodes = np.unique(np.concatenate([edges[e] for e in plate.clamped_edges] + [np.empty(0, np.int64)]))
    return np.sort(np.concatenate([2 * nodes, 2 * nodes + 1])).astype(np.int64)


def symmetry_line_nodes(node_xy: np.ndarray, plate: "Plate") -> np.ndarray:
    """Nodes on y = y0 + height / 2, sorted by x; requires an even plate.ny."""
    if plate.ny % 2:
        raise ScenarioError(
            "plate.ny",
            plate.ny,
            f"must be even so that the symmetry line y = y0 + height/2 = {plate.y0 + plate.height / 2:g} m "
            "is a row of element edges (with Q8 nodes along it)",
        )
    nodes = nodes_on_line(node_xy, 1, plate.y0 + 0.5 * plate.height, GEOMETRY_RTOL * plate.height)
    return nodes[np.argsort(node_xy[nodes, 0], kind="stable")]


# --------------------------------------------------------------------------------------
# Constraints: clamps and rigid layers
# --------------------------------------------------------------------------------------
def rigid_layer_nodes(
    node_xy: np.ndarray, plate: "Plate", x0: float, contact_y: Sequence[float]
) -> tuple[np.ndarray, list[np.ndarray]]:
    """Driving node and layer nodes of each contact on the left edge x = x0.

    Returns (driving, layers): driving[k] is the left-edge node at y_k; layers[k] the
    other left-edge nodes with |y - y_k| <= w/2 (w = plate.layer_width), which move
    with it. Raises ScenarioError for a contact off the plate, between nodes, or
    layers that overlap.
    """
    tol = GEOMETRY_RTOL * plate.height
    left = edge_nodes(node_xy, plate, x0)["left"]
    left_y = node_xy[left, 1]
    half = 0.5 * plate.layer_width
    spacing = plate.height / (2 * plate.ny)
    driving = np.empty(len(contact_y), dtype=np.int64)
    layers: list[np.ndarray] = []
    owner: dict[int, int] = {}
    for k, yk in enumerate(contact_y):
        if not (plate.y0 - tol <= yk <= plate.y0 + plate.height + tol):
            raise ScenarioError(
                "plate.y0",
                plate.y0,
                f"contact {k} at y={yk:g} m lies outside the plate's left edge "
                f"[{plate.y0:g}, {plate.y0 + plate.height:g}] m",
            )
        at = left[np.abs(left_y - yk) <= tol]
        if at.size != 1:
            raise ScenarioError(
                "plate.ny",
                plate.ny,
                f"contact {k} at y={yk:g} m is not on a mesh node; the left-edge node spacing "
                f"is height/(2 ny) = {spacing:g} m; allowed: ny such that (y_contact - y0) is a "
                f"multiple of height/(2 ny) for every contact",
            )
        driving[k] = at[0]
        members = left[np.abs(left_y - yk) <= half + tol]
        for n in members:
            if int(n) in owner:
                j = owner[int(n)]
                raise ScenarioError(
                    "plate.rigid_layer_width",
                    plate.rigid_layer_width,
                    f"the rigid layers of contacts {j} (y={contact_y[j]:g} m) and {k} (y={yk:g} m) "
                    f"share the node at y={node_xy[n, 1]:g} m with w = {plate.layer_width:g} m; "
                    "allowed: w smaller than the distance between neighbouring contacts",
                )
            owner[int(n)] = k
        layers.append(members[members != at[0]])
    return driving, layers


def check_layers_off_clamps(
    fixed: np.ndarray, driving: np.ndarray, layers: Sequence[np.ndarray], plate: "Plate", contact_y: Sequence[float]
) -> None:
    """Refuse a contact on a clamped node, or a rigid layer that reaches one."""
    fixed_nodes = set(int(d) // 2 for d in fixed)
    for k, (d, members) in enumerate(zip(driving, layers)):
        if int(d) in fixed_nodes:
            raise ScenarioError(
                "plate.clamped_edges",
                plate.clamped_edges,
                f"contact {k} at y={contact_y[k]:g} m sits on a clamped node; allowed: contacts on "
                "free parts of the left edge only",
            )
        if any(int(n) in fixed_nodes for n in members):
            raise ScenarioError(
                "plate.rigid_layer_width",
                plate.rigid_layer_width,
                f"the rigid layer of contact {k} at y={contact_y[k]:g} m (w = {plate.layer_width:g} m) "
                "reaches a clamped node; allowed: a width that keeps every layer off the clamped edges",
            )


def rigid_layer_map(
    n_full: int, fixed: np.ndarray, driving: np.ndarray, layers: Sequence[np.ndarray]
) -> tuple[sp.csr_matrix, np.ndarray]:
    """The reduction x_full = T x_red and the reduced indices of the driving dofs.

    Reduced dofs are the full dofs that are neither fixed nor slaved, in increasing
    order. A slaved node's x (y) dof copies its driving node's x (y) dof. Driving and
    slaved nodes must be free (see check_layers_off_clamps). Returns T (n_full, n_red)
    and drive_dofs (n_contacts, 2).
    """
    master = np.arange(n_full)
    free = np.ones(n_full, dtype=bool)
    free[fixed] = False
    for d, members in zip(driving, layers):
        if not free[2 * d] or any(not free[2 * n] for n in members):
            raise ValueError("rigid-layer nodes must be free and belong to one layer only")
        for n in members:
            for c in (0, 1):
                master[2 * n + c] = 2 * d + c
                free[2 * n + c] = False
    reduced_of_full = np.full(n_full, -1, dtype=np.int64)
    reduced_of_full[free] = np.arange(int(free.sum()))
    rows = np.flatnonzero(free | (master != np.arange(n_full)))
    cols = reduced_of_full[master[rows]]
    T = sp.csr_matrix((np.ones(rows.size), (rows, cols)), shape=(n_full, int(free.sum())))
    drive_dofs = np.stack([reduced_of_full[2 * driving], reduced_of_full[2 * driving + 1]], axis=1)
    return T, drive_dofs.reshape(-1, 2).astype(np.int64)


# --------------------------------------------------------------------------------------
# Modes
# --------------------------------------------------------------------------------------
def reduce_matrix(A: sp.spmatrix, T: sp.spmatrix) -> sp.csr_matrix:
    """T^T A T, symmetrised exactly."""
    Ar = (T.T @ A @ T).tocsr()
    return ((Ar + Ar.T) * 0.5).tocsr()


def modal_basis(K_r: sp.spmatrix, M_r: sp.spmatrix, n_modes: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Lowest n_modes (0 = all) of K_r phi = omega^2 M_r phi, dense scipy.linalg.eigh.

    Returns (Phi, omega): Phi (n_red, n_modes) mass-normalised (Phi^T M_r Phi = I),
    each column signed by `fix_mode_signs`; omega [rad/s] ascending (tiny negative
    eigenvalues of rigid motions are clipped to 0).
    """
    n = K_r.shape[0]
    Kd = K_r.toarray() if sp.issparse(K_r) else np.asarray(K_r)
    Md = M_r.toarray() if sp.issparse(M_r) else np.asarray(M_r)
    subset = None if n_modes in (0, n) else [0, n_modes - 1]
    lam, Phi = scipy.linalg.eigh(Kd, Md, subset_by_index=subset)
    return np.ascontiguousarray(fix_mode_signs(Phi)), np.sqrt(np.maximum(lam, 0.0))


def sign_reference(n: int) -> np.ndarray:
    """A fixed, generic weight vector of length n (no symmetry of the mesh maps it to +-itself).

    w_i = 1 + frac(i * golden ratio): positive, aperiodic, the same on every machine.
    """
    return 1.0 + np.modf(np.arange(n) * 0.6180339887498949)[0]


def fix_mode_signs(Phi: np.ndarray) -> np.ndarray:
    """Sign each column of Phi so that sign_reference . phi > 0.

    A deterministic rule that also holds for symmetric and antisymmetric modes, whose
    largest entries come in pairs of opposite sign (a rule based on the largest entry then
    depends on round-off, and two eigensolvers can disagree).
    """
    s = sign_reference(Phi.shape[0]) @ Phi
    return Phi * np.where(s < 0.0, -1.0, 1.0)


# --------------------------------------------------------------------------------------
# The edge load
# --------------------------------------------------------------------------------------
def half_sine_line_load(y: np.ndarray, y0_load: float, length: float) -> np.ndarray:
    """q(y) / q0 = sin(pi (y - y0_load) / L) on [y0_load, y0_load + L], zero elsewhere [-]."""
    s = (y - y0_load) / length
    return np.where((s >= 0.0) & (s <= 1.0), np.sin(np.pi * np.clip(s, 0.0, 1.0)), 0.0)


def _gauss_on(a: float, b: float, n: int) -> tuple[np.ndarray, np.ndarray]:
    """n-point Gauss-Legendre rule on the reference-facet interval [a, b] within [0, 1]."""
    xi, wi = np.polynomial.legendre.leggauss(n)
    return (0.5 * (b - a) * xi + 0.5 * (a + b))[None, :], 0.5 * (b - a) * wi


def edge_load_vector(
    mesh: MeshQuad,
    x_edge: float,
    y0_load: float,
    length: float,
    tol: float,
    n_points: int = EDGE_LOAD_POINTS,
) -> np.ndarray:
    """Consistent nodal forces [N] (x direction) of the half-sine line load, q0 = 1 N/m.

    The load q(y) = sin(pi (y - y0_load) / L) acts on y0_load <= y <= y0_load + L of the
    edge x = x_edge. Each facet is integrated with an n_points Gauss rule over the part
    of it inside the loaded interval (FacetBasis with an explicit quadrature), so a
    load end inside an element is integrated as accurately as one on a node.
    """
    element = ElementVector(ElementQuadS2())
    facets = mesh.facets_satisfying(lambda x: np.abs(x[0] - x_edge) <= tol)
    ya = mesh.p[1, mesh.facets[0, facets]]
    yb = mesh.p[1, mesh.facets[1, facets]]
    lo, hi = y0_load, y0_load + length

    @LinearForm
    def push(v, w):
        return half_sine_line_load(w.x[1], y0_load, length) * v[0]

    f = np.zeros(2 * (mesh.p.shape[1] + mesh.facets.shape[1]))
    groups: dict[tuple[float, float], list[int]] = {}
    for fac, a, b in zip(facets, ya, yb):
        y_lo, y_hi = max(min(a, b), lo), min(max(a, b), hi)  # loaded part of this facet
        if y_hi <= y_lo:
            continue
        s_lo, s_hi = sorted(float(np.clip((y - a) / (b - a), 0.0, 1.0)) for y in (y_lo, y_hi))
        groups.setdefault((s_lo, s_hi), []).append(int(fac))
    for (s_lo, s_hi), facs in groups.items():
        fb = FacetBasis(mesh, element, facets=np.array(facs), quadrature=_gauss_on(s_lo, s_hi, n_points))
        f += asm(push, fb)
    # Shape functions of nodes off a facet vanish on it: clear their round-off (~1e-18).
    on_edge = np.concatenate([mesh.facets[:, facets].ravel(), mesh.p.shape[1] + facets])
    keep = np.zeros_like(f, dtype=bool)
    keep[2 * on_edge] = True
    return np.where(keep, f, 0.0)


# --------------------------------------------------------------------------------------
# Cache
# --------------------------------------------------------------------------------------
def cache_directory() -> Path:
    """$GRANPLATE_CACHE, else ~/.cache/granplate."""
    env = os.environ.get("GRANPLATE_CACHE")
    return Path(env) if env else Path.home() / ".cache" / "granplate"


def cache_key(
    plate: "Plate",
    material: Material,
    x0: float,
    contact_y: Sequence[float],
    edge_load: tuple[float, float] | None,
    symmetry_line: bool,
) -> str:
    """sha256 of every input of build_plate (floats written exactly via repr)."""
    payload = {
        "cache_version": CACHE_VERSION,
        "skfem": getattr(skfem, "__version__", "?"),
        "plate": dataclasses.asdict(plate),
        "material": [material.name, repr(float(material.E)), repr(float(material.nu)), repr(float(material.rho))],
        "x0": repr(float(x0)),
        "contact_y": [repr(float(y)) for y in contact_y],
        "edge_load": None if edge_load is None else [repr(float(v)) for v in edge_load],
        "symmetry_line": symmetry_line,
        "intorder": INTORDER,
        "edge_load_points": EDGE_LOAD_POINTS,
    }
    text = json.dumps(payload, sort_keys=True, default=repr)
    return hashlib.sha256(text.encode()).hexdigest()


def _load_cached(path: Path, key: str) -> dict[str, np.ndarray] | None:
    """The arrays stored at path, or None when missing, unreadable or from another key."""
    if not path.is_file():
        return None
    try:
        with np.load(path, allow_pickle=False) as data:
            if str(data["key"]) != key:
                return None
            return {name: np.array(data[name]) for name in _CACHED_ARRAYS}
    except Exception:  # noqa: BLE001 - any unreadable file just means "recompute"
        return None


def _save_cached(path: Path, key: str, arrays: dict[str, np.ndarray]) -> None:
    """Write arrays atomically (temporary file + rename); failures only warn."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.stem, suffix=".tmp")
        try:
            with os.fdopen(fd, "wb") as fh:
                np.savez(fh, key=np.array(key), **arrays)
            os.replace(tmp, path)
        finally:
            if os.path.exists(tmp):
                os.remove(tmp)
    except OSError as exc:
        warnings.warn(f"granplate: could not write the plate cache {path}: {exc}", stacklevel=3)


# --------------------------------------------------------------------------------------
# Build
# --------------------------------------------------------------------------------------
def _check_plate(plate: "Plate", x0: float, n_modes_max: int | None = None) -> None:
    """Refuse sizes that cannot make a mesh."""
    for name in ("width", "height", "thickness"):
        value = getattr(plate, name)
        if not (np.isfinite(value) and value > 0):
            raise ScenarioError(f"plate.{name}", value, "allowed: a positive length in metres")
    for name in ("nx", "ny"):
        value = getattr(plate, name)
        if not (isinstance(value, (int, np.integer)) and value >= 1):
            raise ScenarioError(f"plate.{name}", value, "allowed: an integer >= 1")
    if plate.layer_width < 0 or not np.isfinite(plate.layer_width):
        raise ScenarioError("plate.rigid_layer_width", plate.rigid_layer_width, "allowed: None or a length >= 0 m")
    if not np.isfinite(x0):
        raise ScenarioError("plate.x0", x0, "allowed: a finite x position in metres")
    if n_modes_max is not None and not (0 <= plate.n_modes <= n_modes_max):
        raise ScenarioError("plate.n_modes", plate.n_modes, f"allowed: 0 (all) or 1..{n_modes_max}")


def _compute_arrays(
    basis: Basis,
    mesh: MeshQuad,
    D: np.ndarray,
    material: Material,
    plate: "Plate",
    x0: float,
    T: sp.csr_matrix,
    edge_load: tuple[float, float] | None,
) -> dict[str, np.ndarray]:
    """The expensive arrays: modes, strain operator, edge load (what the cache holds)."""
    K = assemble_stiffness(basis, D, plate.thickness)
    M = assemble_mass(basis, material.rho, plate.thickness)
    Phi, omega = modal_basis(reduce_matrix(K, T), reduce_matrix(M, T), plate.n_modes)
    op = strain_operator(basis)
    if edge_load is None:
        f = np.zeros(basis.N)
    else:
        f = edge_load_vector(mesh, x0, float(edge_load[0]), float(edge_load[1]), GEOMETRY_RTOL * plate.width)
    return {
        "Phi": Phi,
        "omega": omega,
        "strain_op_data": op.data,
        "strain_op_indices": op.indices,
        "strain_op_indptr": op.indptr,
        "strain_op_shape": np.array(op.shape),
        "edge_load_full": f,
        "edge_load_modal": Phi.T @ (T.T @ f),
    }


def _arrays_fit(arrays: dict[str, np.ndarray], n_full: int, n_red: int, n_modes: int, n_rows: int) -> bool:
    """Whether cached arrays have the shapes this build needs."""
    return (
        arrays["Phi"].shape == (n_red, n_modes)
        and arrays["omega"].shape == (n_modes,)
        and tuple(arrays["strain_op_shape"]) == (n_rows, n_full)
        and arrays["edge_load_full"].shape == (n_full,)
        and arrays["edge_load_modal"].shape == (n_modes,)
    )


def build_plate(
    plate: "Plate",
    x0: float,
    contact_y: Sequence[float],
    edge_load: tuple[float, float] | None = None,
    cache: bool = True,
    material: Material | None = None,
    symmetry_line: bool = True,
) -> PlateModel:
    """Build the plate model (mesh, reduction, modes, output operators).

    plate: the scenario's Plate (plate.x0 is ignored: x0 is given resolved) [m];
    x0: the plate's left edge x [m]; contact_y: the y [m] of each granule contact on the
    left edge (each must be a node; one rigid layer per contact); edge_load = (y0_load, L)
    [m] for the half-sine line load on the left edge, or None; cache: read/write the
    expensive arrays in cache_directory(); material: the plate's Material (None: the
    library's plate.material); symmetry_line: require (even ny) and return the nodes on
    y = y0 + height / 2 (False: symmetry_nodes is empty and ny may be odd).

    Raises ScenarioError for contacts that are not on a free left-edge node, rigid
    layers that overlap or touch a clamp, odd ny when symmetry_line, bad n_modes.
    """
    if material is None:
        if plate.material not in LIBRARY:
            raise ScenarioError("plate.material", plate.material, f"allowed: one of {sorted(LIBRARY)}")
        material = LIBRARY[plate.material]
    x0 = float(x0)
    contact_y = [float(y) for y in contact_y]
    _check_plate(plate, x0)

    mesh = plate_mesh(x0, plate.y0, plate.width, plate.height, plate.nx, plate.ny)
    basis = q8_basis(mesh)
    node_xy = node_coordinates(basis)
    n_full = basis.N
    symmetry_nodes = symmetry_line_nodes(node_xy, plate) if symmetry_line else np.empty(0, dtype=np.int64)
    fixed = clamped_dofs(node_xy, plate, x0)
    driving, layers = rigid_layer_nodes(node_xy, plate, x0, contact_y)
    check_layers_off_clamps(fixed, driving, layers, plate, contact_y)
    T, drive_dofs = rigid_layer_map(n_full, fixed, driving, layers)
    n_red = T.shape[1]
    _check_plate(plate, x0, n_modes_max=n_red)
    n_modes = plate.n_modes or n_red
    n_elem, n_qp = basis.dx.shape
    D = plane_stress_matrix(material.E, material.nu)

    arrays = None
    path = None
    if cache:
        key = cache_key(plate, material, x0, contact_y, edge_load, symmetry_line)
        path = cache_directory() / f"plate-{key[:40]}.npz"
        arrays = _load_cached(path, key)
        if arrays is not None and not _arrays_fit(arrays, n_full, n_red, n_modes, 3 * n_elem * n_qp):
            arrays = None
    if arrays is None:
        arrays = _compute_arrays(basis, mesh, D, material, plate, x0, T, edge_load)
        if cache and path is not None:
            _save_cached(path, key, arrays)

    strain_op = sp.csr_matrix(
        (arrays["strain_op_data"], arrays["strain_op_indices"], arrays["strain_op_indptr"]),
        shape=tuple(int(s) for s in arrays["strain_op_shape"]),
    )
    Phi = arrays["Phi"]
    return PlateModel(
        mesh=mesh,
        basis=basis,
        node_xy=node_xy,
        elements=vtk_elements(mesh),
        T=T,
        Phi=Phi,
        omega=arrays["omega"],
        drive_dofs=drive_dofs,
        phi_drive=np.ascontiguousarray(Phi[drive_dofs.ravel()]),
        edge_load_modal=arrays["edge_load_modal"],
        edge_load_full=arrays["edge_load_full"],
        strain_op=strain_op,
        qp_xy=quadrature_points(basis),
        D=D,
        symmetry_nodes=symmetry_nodes,
        contact_y=np.array(contact_y, dtype=float),
        thickness=float(plate.thickness),
        rho=float(material.rho),
        E=float(material.E),
        nu=float(material.nu),
    )


def transverse_mode_frequencies(model: PlateModel, n: int = 3) -> np.ndarray:
    """Frequencies [Hz] of the n lowest modes whose kinetic energy is mostly along x.

    For a strip clamped at its ends along y these are its in-plane bending modes; the
    others are extensional (along y). Phi is mass-normalised, so v^T M v = 1 per mode.
    """
    M = model.mass_matrix()
    out: list[float] = []
    for j in range(model.n_modes):
        vx = model.T @ model.Phi[:, j]
        vx[1::2] = 0.0
        if vx @ (M @ vx) > 0.5:
            out.append(float(model.omega[j]) / (2.0 * np.pi))
            if len(out) == n:
                break
    return np.array(out)

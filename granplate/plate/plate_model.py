"""A built plate (`PlateModel`): its mesh, reduction, modes and output operators, and what
follows from its modal coordinates: displacements, strains, stresses, the disc-averaged
von Mises stress (docs/model.md section 4.4), its energy and its compliance at the contacts
(paper eq. 8; the truncated basis' static part, section 4.5). `build_plate`
(plate/build.py) makes one.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from skfem import Basis, MeshQuad

from granplate.plate.constraints import reduce_matrix
from granplate.plate.face import face_forces, face_rows
from granplate.plate.fe import assemble_mass, assemble_stiffness
from granplate.plate.stress import gauss_point_strains, max_disc_average, plane_stresses, von_mises_plane_stress


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
    psi: (n_red, 2 n_contacts) static residual shapes of the truncated basis (docs/model.md
        section 4.5): the displacement per unit contact force the kept modes miss
        [m/N]; (n_red, 0) for the full basis.
    resid: (2 n_contacts, 2 n_contacts) = psi at the driving dofs, the residual
        compliance R [m/N]; (0, 0) for the full basis.
    edge_load_modal: (n_modes,) Phi^T T^T edge_load_full [N / kg^1/2 per N/m of q0].
    edge_load_full: (n_full,) consistent nodal forces [N] of the left-edge line load
        q(y) = sin(pi (y - y0_load) / L) for q0 = 1 N/m (zeros when none was asked).
    strain_op: (3 n_elem n_qp, n_full) sparse; rows [component][element][qp] give
        eps_xx, eps_yy, gamma_xy (engineering shear) [-] from x_full [m].
    qp_xy: (n_elem, n_qp, 2) Gauss point coordinates [m].
    D: (3, 3) plane-stress constitutive matrix [Pa].
    symmetry_nodes: node indices on y = y0 + height / 2, sorted by x.
    contact_y: (n_contacts,) contact heights as given [m].
    face_nodes: (n_face,) the nodes of the face x = x0 (the left edge), bottom to top.
    face_y: (n_face,) their heights [m].
    phi_face: (2 n_face, n_modes) mode shapes at the face nodes' dofs, rows [n0 x, n0 y,
        n1 x, ...] [kg^-1/2]: what a patch contact (plate/face.py) averages.
    resid_face: (2 n_face, 2 n_face) residual compliance of the truncated basis between
        the face nodes' dofs (same order) [m/N]: a patch contact's static correction is
        w^T resid_face w (docs/model.md section 4.5); (0, 0) for the full basis.
    thickness [m], rho [kg/m^3], E [Pa], nu [-].
    disc_radius: radius of the stress-averaging discs [m] (Plate.disc_radius);
    disc_centres: (n_discs, 2) their centres [m], a lattice DISC_CENTRE_SPACING x
        disc_radius apart over the plate; disc_op: (n_discs, n_elem n_qp) sparse mean over
        each disc of a Gauss-point field (docs/model.md section 4.4).
    patch_width: width of a patch contact [m] (Plate.layer_width, plate/face.py).
    arrays_key: the run store's key of the stored arrays (mesh, modes, operators) the
        model was built from; "" when built without the store.
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
    psi: np.ndarray
    resid: np.ndarray
    edge_load_modal: np.ndarray
    edge_load_full: np.ndarray
    strain_op: sp.csr_matrix
    qp_xy: np.ndarray
    D: np.ndarray
    symmetry_nodes: np.ndarray
    contact_y: np.ndarray
    face_nodes: np.ndarray
    face_y: np.ndarray
    phi_face: np.ndarray
    resid_face: np.ndarray
    thickness: float
    rho: float
    E: float
    nu: float
    disc_radius: float
    disc_centres: np.ndarray
    disc_op: sp.csr_matrix
    patch_width: float = 0.0
    arrays_key: str = ""

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
    def truncated(self) -> bool:
        """Whether the basis is truncated (with the static residual at the contacts and
        over the face)."""
        return self.psi.shape[1] > 0 or self.resid_face.shape[0] > 0

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
    def full_dofs(self, q: np.ndarray, force: np.ndarray | None = None) -> np.ndarray:
        """x_full = T (Phi q + Psi F) [m]: q (..., n_modes) -> (..., n_full).

        force: the contact forces on the plate F (..., 2 n_contacts) [N], ordered [k0x,
        k0y, k1x, ...]; only the truncated basis uses them (its static part Psi F). Columns
        beyond the rigid layers' are patch contacts (docs/model.md section 3.5) at the
        heights contact_y[n_layers:], each spread by its weights w over the face: their
        static part is the residual response to those nodal forces (`patch_static`)."""
        q = np.asarray(q, dtype=float)
        flat = q.reshape(-1, self.n_modes)
        x_red = self.Phi @ flat.T
        if self.truncated and force is not None:
            n_layer = self.psi.shape[1]
            f = np.asarray(force, dtype=float).reshape(flat.shape[0], -1)
            x_red = x_red + self.psi @ f[:, :n_layer].T
            if f.shape[1] > n_layer:
                x_red = x_red + self.patch_static(f[:, n_layer:])
        x_full = (self.T @ x_red).T
        return x_full.reshape(q.shape[:-1] + (self.n_full,))

    @functools.cached_property
    def patch_psi(self) -> np.ndarray:
        """(n_red, 2 n_patch) static residual shapes of the patch contacts at
        contact_y[n_layers:] [m/N], columns [p0 x, p0 y, p1 x, ...]: (K_r^-1 - Phi
        diag(1/omega^2) Phi^T) E^T w per unit force, E = face_rows (docs/model.md section
        4.5); one sparse factorisation of K_r, computed once per model."""
        heights = self.contact_y[self.psi.shape[1] // 2 :]
        units = np.eye(2 * len(heights))
        f_red = np.asarray(
            face_rows(self.T, self.face_nodes).T @ face_forces(self.face_y, heights, self.patch_width, units).T
        )
        K_r = sp.csc_matrix(reduce_matrix(self.stiffness_matrix(), self.T))
        return spla.splu(K_r).solve(f_red) - self.Phi @ ((self.Phi.T @ f_red) / self.omega[:, None] ** 2)

    def patch_static(self, force: np.ndarray) -> np.ndarray:
        """(n_red, n_times) static displacement the truncated basis' kept modes miss [m]
        under the patch contacts' forces (n_times, 2 n_patch) [N]: patch_psi F."""
        return self.patch_psi @ np.asarray(force, dtype=float).T

    def full_displacement(self, q: np.ndarray, force: np.ndarray | None = None) -> np.ndarray:
        """Nodal displacements [m]: q (..., n_modes) -> (..., n_nodes, 2) (force: see full_dofs)."""
        x_full = self.full_dofs(q, force)
        return x_full.reshape(x_full.shape[:-1] + (-1, 2))

    def strains(self, q: np.ndarray, force: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """eps_xx, eps_yy, gamma_xy [-] at the Gauss points, each (..., n_elem, n_qp)."""
        return gauss_point_strains(self.strain_op, self.full_dofs(q, force), self.qp_xy.shape[0], self.n_qp)

    def stresses(self, q: np.ndarray, force: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """sigma_xx, sigma_yy, tau_xy [Pa] at the Gauss points, each (..., n_elem, n_qp)."""
        return plane_stresses(self.D, *self.strains(q, force))

    def von_mises(self, q: np.ndarray, force: np.ndarray | None = None) -> np.ndarray:
        """Plane-stress von Mises stress [Pa] (docs/model.md section 4.4, eq. 12) at the Gauss points.

        sqrt(sxx^2 - sxx syy + syy^2 + 3 sxy^2), shape (..., n_elem, n_qp).
        """
        sxx, syy, sxy = self.stresses(q, force)
        return von_mises_plane_stress(sxx, syy, sxy)

    def max_disc_von_mises(self, von_mises: np.ndarray) -> np.ndarray:
        """Largest von Mises stress averaged over a disc of radius disc_radius [Pa]
        (docs/model.md section 4.4), from Gauss-point values (..., n_elem, n_qp) -> (...)."""
        vm = np.asarray(von_mises)
        return max_disc_average(self.disc_op, vm.reshape(vm.shape[:-2] + (-1,)))

    def energy(self, q: np.ndarray, qdot: np.ndarray, force: np.ndarray | None = None) -> np.ndarray:
        """Plate energy [J]: 1/2 qdot.qdot + 1/2 sum omega^2 q^2 (= 1/2 v^T M v + 1/2 x^T K x),
        plus the truncated basis' static part 1/2 F^T R F (docs/model.md section 4.5)."""
        q = np.asarray(q, dtype=float)
        qdot = np.asarray(qdot, dtype=float)
        e = 0.5 * np.sum(qdot**2, axis=-1) + 0.5 * np.sum(self.omega**2 * q**2, axis=-1)
        if self.truncated and force is not None:
            f = np.asarray(force, dtype=float)
            e = e + 0.5 * np.einsum("...i,ij,...j->...", f, self.resid, f)
        return e

    def compliance(self, dt: float) -> np.ndarray:
        """Driving-dof block of (M_r + dt^2 K_r / 4)^-1 [1/kg] (paper eq. 8), (2 nc, 2 nc).

        = phi_drive diag(1 / (1 + dt^2 omega^2 / 4)) phi_drive^T; rows/columns ordered
        [k0x, k0y, k1x, k1y, ...]. With all modes kept this is exact; the truncated basis
        adds its missing modes quasi-statically, 4 R / dt^2 (docs/model.md section 4.5).
        """
        weights = 1.0 / (1.0 + 0.25 * dt**2 * self.omega**2)
        g = (self.phi_drive * weights) @ self.phi_drive.T
        if self.truncated:
            g = g + 4.0 * self.resid / dt**2
        return g

    def static_compliance(self) -> np.ndarray:
        """Driving-dof block of K_r^-1 [m/N] as the basis represents it:
        phi_drive diag(1/omega^2) phi_drive^T (+ R for the truncated basis)."""
        g = (self.phi_drive / self.omega**2) @ self.phi_drive.T
        if self.truncated:
            g = g + self.resid
        return g

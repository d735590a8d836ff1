"""Build the plate model: mesh, reduction, modes and output operators, cached on disk.

Data flows one way::

    Plate, Material -> mesh, basis -> K, M (full)            assemble_stiffness, assemble_mass
                    -> T (clamps + rigid layers)             clamped_dofs, rigid_layer_map
                    -> K_r = T^T K T, M_r = T^T M T -> Phi, omega   modal_basis
                    -> strain_op, edge_load_full                    strain_operator, edge_load_vector

A full displacement vector is x_full = T @ x_red with x_red = Phi @ q, q the modal
coordinates. The expensive part of `build_plate` (assembly and the dense generalized
eigenproblem) is kept in the run store (`granplate.store`, kind "plate"), keyed by every
input (`cache_payload`).
"""

from __future__ import annotations

import dataclasses
import functools
import logging
from dataclasses import dataclass
from typing import TYPE_CHECKING, Callable, Sequence

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
import skfem
from skfem import Basis, MeshQuad

from granplate.plate.errors import PlateError, plate_inputs
from granplate import store
from granplate.plate.constraints import (
    GEOMETRY_RTOL,
    clamped_dofs,
    reduce_matrix,
    rigid_layer_map,
    rigid_layer_nodes,
    symmetry_line_nodes,
)
from granplate.plate.face import face_forces, face_modes, face_nodes, face_rows
from granplate.plate.fe import assemble_mass, assemble_stiffness, node_coordinates, plate_mesh, q8_basis, vtk_elements
from granplate.plate.load import EDGE_LOAD_POINTS, edge_load_vector
from granplate.plate.modes import modal_basis, residual_compliance, truncated_modal_basis, weyl_mode_count
from granplate.plate.stress import (
    DISC_CENTRE_SPACING,
    INTORDER,
    disc_average_operator,
    disc_centres,
    gauss_point_strains,
    max_disc_average,
    plane_stress_matrix,
    plane_stresses,
    quadrature_points,
    strain_operator,
    von_mises_plane_stress,
)
from granplate.setup.materials import LIBRARY, Material
from granplate.setup.plate_checks import check_layers_off_clamps, check_mode_count, check_plate_fields
from granplate.setup.plate_cost import (
    DEFAULT_MAX_FREQUENCY,
    basis_kind,
    build_estimate,
    check_fits,
    truncation_supported,
)

if TYPE_CHECKING:  # pragma: no cover
    from granplate.setup.scenario import Plate

log = logging.getLogger(__name__)
#: A plate build estimated to take at least this long [s] is announced (log, INFO).
NOTE_BUILD_SECONDS = 2.0


def build_note(plate: "Plate", kind: str, n_red: int, n_face: int) -> str | None:
    """The line announcing a plate build estimated (setup.plate_cost) to take at least
    NOTE_BUILD_SECONDS; None for a quicker one."""
    seconds = build_estimate(kind, n_red, n_face)[1]
    if seconds < NOTE_BUILD_SECONDS:
        return None
    what = (
        f"all {n_red} modes (dense)"
        if kind == "all"
        else f"modes below {plate.max_frequency or DEFAULT_MAX_FREQUENCY:.3g} Hz and the static correction "
        f"({n_red} dofs)"
    )
    return f"building the {plate.nx} x {plate.ny} plate: {what} (about {seconds:.0f} s; cached afterwards) ..."


#: The run store's kind of the plate's cached arrays.
STORE_KIND = "plate"
#: Bump when anything that changes the cached arrays changes (formulas, ordering, dtypes).
PLATE_FORMAT = 3

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


def cache_payload(
    plate: "Plate",
    material: Material,
    x0: float,
    contact_y: Sequence[float],
    edge_load: tuple[float, float] | None,
    symmetry_line: bool,
    kind: str = "all",
) -> dict:
    """Every input of build_plate, for the run store's key (floats written exactly via repr).

    kind: the basis ("all" or "truncated"); the fields choosing it (modes, max_frequency)
    enter the key only for the truncated basis, so the full one keeps its key."""
    fields = dataclasses.asdict(plate)
    fields.pop("modes", None)
    fields.pop("stress_radius", None)  # an output setting: the cached arrays do not depend on it
    max_frequency = fields.pop("max_frequency", None)
    if kind == "truncated":
        fields["basis"] = ["truncated", repr(float(max_frequency or DEFAULT_MAX_FREQUENCY))]
    return {
        "skfem": getattr(skfem, "__version__", "?"),
        "plate": fields,
        "material": [material.name, repr(float(material.E)), repr(float(material.nu)), repr(float(material.rho))],
        "x0": repr(float(x0)),
        "contact_y": [repr(float(y)) for y in contact_y],
        "edge_load": None if edge_load is None else [repr(float(v)) for v in edge_load],
        "symmetry_line": symmetry_line,
        "intorder": INTORDER,
        "edge_load_points": EDGE_LOAD_POINTS,
    }


def _check_plate(plate: "Plate", x0: float, n_modes_max: int | None = None) -> None:
    """Refuse sizes that cannot make a mesh (setup.plate_checks' ranges; n_modes_max: the
    reduced dofs, once known)."""
    with plate_inputs():
        check_plate_fields(plate, x0)
        if n_modes_max is not None:
            check_mode_count(plate, n_modes_max)


def _compute_arrays(
    basis: Basis,
    mesh: MeshQuad,
    D: np.ndarray,
    material: Material,
    plate: "Plate",
    x0: float,
    T: sp.csr_matrix,
    edge_load: tuple[float, float] | None,
    kind: str,
    drive: np.ndarray,
    face: np.ndarray,
) -> dict[str, np.ndarray]:
    """The expensive arrays: modes (kind "all": dense, every mode; "truncated": sparse, up
    to the cut-off, with the static residual shapes psi at the drive dofs and the residual
    compliance resid_face over the face nodes' dofs), strain operator, edge load (what the
    cache holds)."""
    K = assemble_stiffness(basis, D, plate.thickness)
    M = assemble_mass(basis, material.rho, plate.thickness)
    K_r, M_r = reduce_matrix(K, T), reduce_matrix(M, T)
    del K, M
    if kind == "truncated":
        max_omega = 2.0 * np.pi * float(plate.max_frequency or DEFAULT_MAX_FREQUENCY)
        expected = weyl_mode_count(plate.width * plate.height, material.E, material.nu, material.rho, max_omega)
        Phi, omega, psi, resid_face = truncated_modal_basis(
            K_r, M_r, drive, max_omega, plate.n_modes, expected, face=face_rows(T, face)
        )
    else:
        Phi, omega = modal_basis(K_r, M_r, plate.n_modes)
        psi = np.zeros((T.shape[1], 0))
        resid_face = np.zeros((0, 0))
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
        "psi": psi,
        "resid_face": resid_face,
    }


def _arrays_fit(
    arrays: dict[str, np.ndarray], n_full: int, n_red: int, n_modes: int | None, n_rows: int, n_face: int = 0
) -> bool:
    """Whether cached arrays are all there, with the shapes this build needs (n_modes
    None: any number, the truncated basis', which also needs psi and the (2 n_face,
    2 n_face) resid_face)."""
    if not all(name in arrays for name in _CACHED_ARRAYS):
        return False
    if n_modes is None and not (
        "psi" in arrays
        and arrays["psi"].shape[0] == n_red
        and "resid_face" in arrays
        and arrays["resid_face"].shape == (2 * n_face, 2 * n_face)
    ):
        return False
    n_modes = arrays["omega"].shape[0] if n_modes is None else n_modes
    return (
        arrays["Phi"].shape == (n_red, n_modes)
        and arrays["omega"].shape == (n_modes,)
        and tuple(arrays["strain_op_shape"]) == (n_rows, n_full)
        and arrays["edge_load_full"].shape == (n_full,)
        and arrays["edge_load_modal"].shape == (n_modes,)
    )


def _reduction(
    node_xy: np.ndarray, plate: "Plate", x0: float, contact_y: Sequence[float], n_full: int
) -> tuple[sp.csr_matrix, np.ndarray]:
    """T and drive_dofs of the clamps and rigid layers (PlateError when they clash)."""
    fixed = clamped_dofs(node_xy, plate, x0)
    driving, layers = rigid_layer_nodes(node_xy, plate, x0, contact_y)
    with plate_inputs():
        check_layers_off_clamps(plate, contact_y, list(zip(driving, layers)), {int(d) // 2 for d in fixed})
    return rigid_layer_map(n_full, fixed, driving, layers)


def _stored_or_computed(
    payload: dict | None, fits: Callable[[dict], bool], compute: Callable[[], dict]
) -> dict[str, np.ndarray]:
    """The arrays the run store holds for payload when they fit, else compute() (then
    stored; a process building the same plate at the same time is waited for, and its
    arrays read); payload None: neither read nor write the store."""
    if payload is None:
        return compute()
    arrays = store.load_arrays(STORE_KIND, payload, PLATE_FORMAT)
    if arrays is not None and fits(arrays):
        return arrays
    with store.exclusive(STORE_KIND, payload, PLATE_FORMAT):  # one process builds, the others wait and read
        arrays = store.load_arrays(STORE_KIND, payload, PLATE_FORMAT)
        if arrays is not None and fits(arrays):
            return arrays
        arrays = compute()
        store.save_arrays(STORE_KIND, payload, PLATE_FORMAT, arrays)
    return arrays


#: Plates built in this process, most recent last: memo key -> PlateModel (the designs of a
#: study that share a plate build it once per process).
_BUILT: dict[str, "PlateModel"] = {}
#: How many built plates a process keeps.
BUILT_KEPT = 4


def memo_key(
    plate: "Plate",
    material: Material,
    x0: float,
    contact_y: Sequence[float],
    edge_load: tuple[float, float] | None,
    symmetry_line: bool,
) -> str:
    """What identifies a built plate in this process: every input of build_plate, the
    output settings and the basis choice included (floats written exactly via repr), and
    the run store's directory (another store builds, and fills, its own)."""
    fields = {k: repr(v) for k, v in sorted(dataclasses.asdict(plate).items())}
    return repr(
        (
            fields,
            material.name,
            repr(float(material.E)),
            repr(float(material.nu)),
            repr(float(material.rho)),
            repr(float(x0)),
            [repr(float(y)) for y in contact_y],
            None if edge_load is None else [repr(float(v)) for v in edge_load],
            bool(symmetry_line),
            getattr(skfem, "__version__", "?"),
            INTORDER,
            EDGE_LOAD_POINTS,
            PLATE_FORMAT,
            str(store.cache_directory()),
        )
    )


def forget_built_plates() -> None:
    """Drop the plates this process keeps in memory (the next build_plate reads the store)."""
    _BUILT.clear()


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
    expensive arrays in the run store, and keep the built plate in this process's memory
    (the last BUILT_KEPT plates, keyed by every input: the same plate asked again is the
    same object, which callers must not modify); material: the plate's Material (None: the
    library's plate.material); symmetry_line: require (even ny) and return the nodes on
    y = y0 + height / 2 (False: symmetry_nodes is empty and ny may be odd).

    Raises PlateError for contacts that are not on a free left-edge node, rigid
    layers that overlap or touch a clamp, odd ny when symmetry_line, bad sizes or
    n_modes (a scenario is refused earlier, by granplate.setup.validate).
    """
    if material is None:
        if plate.material not in LIBRARY:
            raise PlateError("plate.material", plate.material, f"allowed: one of {sorted(LIBRARY)}")
        material = LIBRARY[plate.material]
    x0 = float(x0)
    contact_y = [float(y) for y in contact_y]
    if not cache:
        return _build_plate(plate, x0, contact_y, edge_load, False, material, symmetry_line)
    key = memo_key(plate, material, x0, contact_y, edge_load, symmetry_line)
    built = _BUILT.pop(key, None)
    if built is None:
        built = _build_plate(plate, x0, contact_y, edge_load, True, material, symmetry_line)
    _BUILT[key] = built  # most recent last
    while len(_BUILT) > BUILT_KEPT:
        _BUILT.pop(next(iter(_BUILT)))
    return built


def _build_plate(
    plate: "Plate",
    x0: float,
    contact_y: list[float],
    edge_load: tuple[float, float] | None,
    cache: bool,
    material: Material,
    symmetry_line: bool,
) -> PlateModel:
    """build_plate without the process's memory: the mesh, reduction and operators built,
    the expensive arrays from the run store (cache) or computed."""
    _check_plate(plate, x0)

    mesh = plate_mesh(x0, plate.y0, plate.width, plate.height, plate.nx, plate.ny)
    basis = q8_basis(mesh)
    node_xy = node_coordinates(basis)
    n_full = basis.N
    symmetry_nodes = symmetry_line_nodes(node_xy, plate) if symmetry_line else np.empty(0, dtype=np.int64)
    T, drive_dofs = _reduction(node_xy, plate, x0, contact_y, n_full)
    n_red = T.shape[1]
    _check_plate(plate, x0, n_modes_max=n_red)
    kind = basis_kind(
        getattr(plate, "modes", "all"), n_red, truncation_supported(plate.clamped_edges, edge_load is not None)
    )
    n_modes = None if kind == "truncated" and not plate.n_modes else (plate.n_modes or n_red)
    n_elem, n_qp = basis.dx.shape
    D = plane_stress_matrix(material.E, material.nu)
    face = face_nodes(node_xy, x0, GEOMETRY_RTOL * plate.width)

    def compute() -> dict[str, np.ndarray]:
        check_fits(kind, n_red, getattr(plate, "modes", "all"), n_face=len(face))
        note = build_note(plate, kind, n_red, len(face))
        if note is not None:
            log.info(note)
        return _compute_arrays(basis, mesh, D, material, plate, x0, T, edge_load, kind, drive_dofs, face)

    payload = cache_payload(plate, material, x0, contact_y, edge_load, symmetry_line, kind) if cache else None
    arrays = _stored_or_computed(
        payload,
        lambda a: _arrays_fit(a, n_full, n_red, n_modes, 3 * n_elem * n_qp, len(face)),
        compute,
    )

    strain_op = sp.csr_matrix(
        (arrays["strain_op_data"], arrays["strain_op_indices"], arrays["strain_op_indptr"]),
        shape=tuple(int(s) for s in arrays["strain_op_shape"]),
    )
    Phi = arrays["Phi"]
    psi = arrays["psi"] if "psi" in arrays else np.zeros((n_red, 0))
    resid_face = arrays["resid_face"] if kind == "truncated" else np.zeros((0, 0))
    qp_xy = quadrature_points(basis)
    radius = float(plate.disc_radius)
    centres = disc_centres(x0, plate.y0, plate.width, plate.height, DISC_CENTRE_SPACING * radius)
    disc_op = disc_average_operator(qp_xy.reshape(-1, 2), np.asarray(basis.dx).ravel(), centres, radius)
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
        psi=psi,
        resid=residual_compliance(psi, drive_dofs) if psi.shape[1] else np.zeros((0, 0)),
        edge_load_modal=arrays["edge_load_modal"],
        edge_load_full=arrays["edge_load_full"],
        strain_op=strain_op,
        qp_xy=qp_xy,
        D=D,
        symmetry_nodes=symmetry_nodes,
        contact_y=np.array(contact_y, dtype=float),
        face_nodes=face,
        face_y=np.ascontiguousarray(node_xy[face, 1]),
        phi_face=face_modes(T, Phi, face),
        resid_face=np.ascontiguousarray(resid_face, dtype=float),
        thickness=float(plate.thickness),
        rho=float(material.rho),
        E=float(material.E),
        nu=float(material.nu),
        disc_radius=radius,
        disc_centres=centres,
        disc_op=disc_op,
        patch_width=float(plate.layer_width),
        arrays_key=store.key(STORE_KIND, payload, PLATE_FORMAT) if payload is not None else "",
    )

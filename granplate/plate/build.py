"""Build the plate model: mesh, reduction, modes and output operators, cached on disk.

Data flows one way::

    Plate, Material -> mesh, basis -> K, M (full)            assemble_stiffness, assemble_mass
                    -> T (clamps + rigid layers)             clamped_dofs, rigid_layer_map
                    -> K_r = T^T K T, M_r = T^T M T -> Phi, omega   modal_basis
                    -> strain_op, edge_load_full                    strain_operator, edge_load_vector

A full displacement vector is x_full = T @ x_red with x_red = Phi @ q, q the modal
coordinates. The expensive part of `build_plate` (assembly and the dense generalized
eigenproblem) is kept in the run store (`granplate.store`, kind "plate"), keyed by every
input (`cache_payload`). The built plate, `PlateModel`, has a module of its own
(plate/plate_model.py) and is importable from here too.
"""

from __future__ import annotations

import dataclasses
import logging
from typing import TYPE_CHECKING, Callable, Sequence

import numpy as np
import scipy.sparse as sp
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
from granplate.plate.face import face_modes, face_nodes, face_rows
from granplate.plate.fe import assemble_mass, assemble_stiffness, node_coordinates, plate_mesh, q8_basis, vtk_elements
from granplate.plate.load import EDGE_LOAD_POINTS, edge_load_vector
from granplate.plate.plate_model import PlateModel
from granplate.plate.modes import modal_basis, residual_compliance, truncated_modal_basis, weyl_mode_count
from granplate.plate.stress import (
    DISC_CENTRE_SPACING,
    INTORDER,
    disc_average_operator,
    disc_centres,
    plane_stress_matrix,
    quadrature_points,
    strain_operator,
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

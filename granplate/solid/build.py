"""Build a solid: mesh, elements, supports, modes below the cut-off and the residual
compliance over one face's dofs, with its arrays kept in the run store.

Data flows one way::

    Solid, Material -> mesh (box or file), scalar basis -> K, M     solid.mesh, solid.fe
                    -> fixed dofs, reduced system (dofs)             solid.boundary
                    -> cost checked (before anything heavy)          solid.cost
                    -> omega, Phi (rigid-body modes of a free body)  solid.modes
                    -> R over the surface dofs                       solid.residual

The residual's factorisation runs in a second thread beside the eigensolver
(`modes_and_residual`): a cold build takes about the eigensolver's time, not the sum.

The residual compliance is kept over the normal dofs of one face (default: zmax, the
z dofs): a granule pressing on the face loads mainly those, and |S| is a third of all the
face's dofs, a ninth of the dense matrix and a third of the solves. `components="xyz"`
keeps all three.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import logging
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
import scipy.sparse as sp
import skfem

from granplate import store
from granplate.errors import ScenarioError
from granplate.setup.materials import LIBRARY, Material
from granplate.setup.scenario import Solid
from granplate.setup.threads import available_threads
from granplate.setup.solid_checks import check_faces, check_solid_fields
from granplate.solid.boundary import face_node_dofs, face_nodes, fixed_dofs, free_dofs, reduced, reduced_index
from granplate.solid.cost import SolidCost, box_dofs, check_fits, estimate, mode_count, omega_below
from granplate.solid.fe import is_hexahedral, mass_matrix, node_coordinates, scalar_basis, stiffness_matrix
from granplate.solid.mesh import box_mesh, face_names, read_mesh
from granplate.solid.factor import one_blas_thread
from granplate.solid.modes import modes_below, rigid_body_modes, rigid_modes, split_plan
from granplate.solid.residual import (
    flexibility,
    flexibility_block,
    static_factor,
    static_flexibility,
    truncation_residual,
)

log = logging.getLogger(__name__)

#: The run store's kind of the solid's arrays.
STORE_KIND = "solid"
#: Bump when anything that changes the stored arrays changes.
SOLID_FORMAT = 3
#: Share of the machine's physical memory a solid may take.
MEMORY_SHARE = 0.7
#: One window holds WINDOW_MARGIN times the estimated modes (plus 10), at most MAX_WINDOW;
#: CLAMPED_MARGIN on a body clamped somewhere, whose count the estimate exceeds (no
#: boundary term: a clamp lowers it; 130 estimated against 107 on the bench's plate).
WINDOW_MARGIN = 1.2
CLAMPED_MARGIN = 1.0
MAX_WINDOW = 400
_ARRAYS = ("omega", "Phi", "dofs", "surface_dofs", "resid")


@dataclass(frozen=True)
class SolidModel:
    """A built solid. Node n has the full dofs 3n + c (c = 0, 1, 2: x, y, z).

    nodes: (n_nodes, 3) node coordinates [m] (corners and mid-nodes);
    dofs: (n_red,) the full dof of each reduced dof (the free ones, ascending);
    omega: (n_modes,) angular frequencies [rad/s] ascending (a free body's six rigid-body
        modes first, at 0); Phi: (n_red, n_modes) M-orthonormal modes [kg^-1/2];
    surface_dofs: (n_s,) the reduced dofs of the residual compliance (a face's normal
        dofs by default); resid: (n_s, n_s) the residual compliance there [m/N];
    faces: face name -> its node indices; element, material; free: held nowhere;
    cost: the estimate it was checked against; mesh, basis: the skfem mesh and scalar
    basis (rebuilt, not stored); arrays_key: the run store's key ("" unstored).

    `residual_block(rows)` gives the residual compliance over any reduced dofs on demand
    from one factorisation kept in memory (built on first use): what a contact patch needs,
    without the whole face's matrix.
    """

    nodes: np.ndarray
    dofs: np.ndarray
    omega: np.ndarray
    Phi: np.ndarray
    surface_dofs: np.ndarray
    resid: np.ndarray
    faces: dict
    element: str
    material: Material
    free: bool
    cost: SolidCost
    mesh: skfem.Mesh = None
    basis: skfem.Basis = None
    arrays_key: str = ""
    rigid_patches: tuple = ()  # setup.scenario.RigidPatch: the surface tied rigid there (solid.tie)

    @functools.cached_property
    def _flexibility(self) -> Callable[[np.ndarray], np.ndarray]:
        """The static (held) or inertia-relief (free) flexibility's solver, one LU."""
        K = reduced(solid_stiffness(self.basis, self.mesh, self.element, self.material, self.rigid_patches), self.dofs)
        M = reduced(mass_matrix(self.basis, self.material.rho), self.dofs)
        return flexibility(K, self.nodes[self.dofs // 3], M, self.Phi[:, :6] if self.free else None)

    def residual_block(self, rows: np.ndarray) -> np.ndarray:
        """R[rows, rows] [m/N] over reduced dofs `rows` (solid.residual), on demand."""
        rows = np.asarray(rows, dtype=np.int64)
        G = flexibility_block(self._flexibility, len(self.dofs), rows)
        elastic = self.omega > 0.0
        phi = self.Phi[rows][:, elastic]
        R = G - (phi / self.omega[elastic] ** 2) @ phi.T
        return 0.5 * (R + R.T)

    @property
    def n_modes(self) -> int:
        """Kept modes (rigid-body ones included)."""
        return self.omega.shape[0]

    @property
    def frequencies(self) -> np.ndarray:
        """omega / 2 pi [Hz]."""
        return self.omega / (2.0 * np.pi)


def solid_stiffness(
    sbasis: skfem.Basis, mesh: skfem.Mesh, element: str, material: Material, rigid_patches: tuple = ()
) -> "sp.csr_matrix":
    """K [N/m] on the full dofs, with the rigid patches' ties (solid.tie) added."""
    K = stiffness_matrix(sbasis, material.E, material.nu)
    if not rigid_patches:
        return K
    from granplate.solid.fe import vector_basis
    from granplate.solid.surface import boundary_surface
    from granplate.solid.tie import facing_nodes, patch_nodes, tie_penalty

    surface = boundary_surface(vector_basis(mesh, element))
    nodes = [
        patch_nodes(*facing_nodes(surface, rp.centre), rp.centre, rp.radius, k, rp.axis)
        for k, rp in enumerate(rigid_patches)
    ]
    return K + tie_penalty(K, node_coordinates(sbasis), nodes, [rp.rotates for rp in rigid_patches])


def solid_mesh(sd: Solid) -> skfem.Mesh:
    """The solid's mesh (a box, or its file read and checked)."""
    if sd.mesh is not None:
        mesh = read_mesh(sd.mesh)
        if is_hexahedral(sd.element) != isinstance(mesh, skfem.MeshHex):
            raise ScenarioError(
                "plate.element",
                sd.element,
                "does not fit the mesh file's cells: use "
                + ("'hex20' or 'hex27'" if isinstance(mesh, skfem.MeshHex) else "'tet10'"),
            )
        check_faces(sd, face_names(mesh))
        return mesh
    return box_mesh(sd.size, sd.elements, sd.origin or (0.0, 0.0, 0.0), tetrahedra=not is_hexahedral(sd.element))


def cache_payload(sd: Solid, material: Material, surface: str | None, components: str) -> dict:
    """Every input of build_solid (a mesh file by its content's SHA-256)."""
    fields = dataclasses.asdict(sd)
    for name in ("stress_radius", "patch_radius"):  # the outputs' averaging and the contacts, not the body
        fields.pop(name, None)
    if sd.mesh is not None:
        fields["mesh"] = hashlib.sha256(Path(sd.mesh).read_bytes()).hexdigest()
    return {
        "skfem": getattr(skfem, "__version__", "?"),
        "solid": fields,
        "material": [material.name, repr(float(material.E)), repr(float(material.nu)), repr(float(material.rho))],
        "surface": surface,
        "components": components,
    }


def solid_cost(sd: Solid, material: Material, n_dofs: int, xyz: np.ndarray, n_surface: int) -> SolidCost:
    """The estimate (solid.cost) of the modes and the residual compliance."""
    extent = xyz.max(axis=0) - xyz.min(axis=0)
    if sd.elements is not None:
        _, separator = box_dofs(tuple(sd.elements), sd.element)
    else:  # a mesh file: the dofs within a node spacing of the mid-plane across the longest side
        axis = int(np.argmax(extent))
        spacing = (float(np.prod(np.maximum(extent, 1e-300))) / max(len(xyz) / 3, 1)) ** (1.0 / 3.0)
        separator = max(1, int(np.sum(np.abs(xyz[:, axis] - np.median(xyz[:, axis])) <= spacing)))
    n_modes = mode_count(tuple(extent), material.E, material.nu, material.rho, 2 * np.pi * sd.max_frequency)
    return estimate(n_dofs, separator, n_modes, n_surface, window_size(n_modes, n_dofs, bool(sd.clamped)))


def window_size(n_modes: int, n_dofs: int, clamped: bool = False) -> int:
    """Eigenvalues per shift-invert window: the estimated mode count and a margin, so that
    one window usually holds them all (one factorisation; measured on the 40 x 40 x 2
    plate's 12,255-dof twin: 31 s in one window of 140 against 92 s in windows of 60).
    The Lanczos steps grow with the window (about 2.5 per value asked, each a solve and
    a reorthogonalisation): a clamped body's smaller margin cut the plate's set-up from
    70.3 s (166 values, 418 solves) to 64.7 s (140 values); a mode the window misses is
    found by the next window."""
    margin = CLAMPED_MARGIN if clamped else WINDOW_MARGIN
    return int(np.clip(int(margin * n_modes) + 10, 20, MAX_WINDOW))


def window_plan(extent: np.ndarray, material: Material, max_omega: float, k: int) -> tuple:
    """The eigensolver's first windows (solid.modes.split_plan), the second one shifted by
    the Weyl estimate (solid.cost.mode_count) of a body of these sides [m]."""
    size = tuple(float(e) for e in extent)
    return split_plan(
        k,
        max_omega**2,
        lambda c: omega_below(c, size, material.E, material.nu, material.rho) ** 2,  # type: ignore[arg-type]
    )


def modes_and_residual(
    K: sp.spmatrix,
    M: sp.spmatrix,
    max_omega: float,
    xyz: np.ndarray,
    nodes: np.ndarray,
    free: bool,
    surface_dofs: np.ndarray,
    k: int,
    plan: tuple = (),
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(omega, Phi, R over surface_dofs) of the reduced K, M (solid.modes, solid.residual).

    The residual's factorisation (solid.residual.static_factor) needs no elastic mode: it
    and the eigensolver's planned windows (solid.modes: plan) share a pool of threads, one
    per core numba may use (NUMBA_NUM_THREADS: a design study's worker has one; SuperLU
    and ARPACK release the GIL), the windows first (the first, the smaller, then leaves
    its core to the factorisation), each on one BLAS thread; the dense part of the
    residual (the factor's trailing block and its inverse, the largest arrays) waits for
    the eigensolver's end, which frees the shifted factorisations, and has every BLAS
    thread. The outer pin spans the threads' whole life, so their BLAS limits cannot race."""
    rigid = m_rigid = None
    if free:
        rigid, m_rigid = rigid_body_modes(nodes), rigid_modes(nodes, M)
    tasks = max(1, len(plan)) + bool(surface_dofs.size)
    factor: list = []
    with ThreadPoolExecutor(max_workers=max(1, min(tasks, available_threads())), thread_name_prefix="solid") as pool:
        with one_blas_thread():

            def residual_factor() -> None:
                factor.append(pool.submit(static_factor, K, surface_dofs, xyz, m_rigid))

            then = residual_factor if surface_dofs.size else None
            omega, Phi = modes_below(K, M, max_omega, xyz, rigid=rigid, k=k, plan=plan, pool=pool, then=then)
            schur = factor.pop().result() if factor else None
    if schur is None:
        return omega, Phi, np.zeros((0, 0))
    G = static_flexibility(K, surface_dofs, xyz, M, m_rigid, factor=schur)
    del schur  # the LU, before the residual's dense arrays
    return omega, Phi, truncation_residual(G, Phi[surface_dofs], omega)


def _stored_or_computed(payload: dict | None, compute: Callable[[], dict]) -> dict:
    """The run store's arrays for payload, else compute() (then stored)."""
    if payload is None:
        return compute()
    arrays = store.load_arrays(STORE_KIND, payload, SOLID_FORMAT)
    if arrays is not None and all(k in arrays for k in _ARRAYS):
        return arrays
    with store.exclusive(STORE_KIND, payload, SOLID_FORMAT):
        arrays = store.load_arrays(STORE_KIND, payload, SOLID_FORMAT)
        if arrays is not None and all(k in arrays for k in _ARRAYS):
            return arrays
        arrays = compute()
        store.save_arrays(STORE_KIND, payload, SOLID_FORMAT, arrays)
    return arrays


#: Solids built in this process, most recent last: run-store key and store directory ->
#: SolidModel (a study's designs, a benchmark's repeats, reuse the object: its mesh, bases
#: and flexibility factorisation, which callers must not modify).
_BUILT: dict[tuple[str, str], SolidModel] = {}
#: How many built solids a process keeps.
BUILT_KEPT = 2


def forget_built_solids() -> None:
    """Drop the solids this process keeps in memory (the next build_solid reads the store)."""
    _BUILT.clear()


def build_solid(
    sd: Solid,
    material: Material | None = None,
    surface: str | None = "zmax",
    components: str = "z",
    cache: bool = True,
    memory: float | None = None,
    seconds: float | None = None,
) -> SolidModel:
    """Build the solid (module docstring).

    surface: the face whose dofs get the residual compliance (None: none);
    components: which of its nodes' dofs ("z", "xyz", ...); cache: the run store, and the
    last BUILT_KEPT solids kept in this process (the same inputs give the same object);
    memory [bytes] / seconds: the limits the estimate is checked against (memory None:
    MEMORY_SHARE of the machine's memory). ScenarioError for bad fields or a body too big.
    """
    check_solid_fields(sd)
    if material is None:
        if sd.material not in LIBRARY:
            raise ScenarioError("plate.material", sd.material, f"allowed: one of {sorted(LIBRARY)}")
        material = LIBRARY[sd.material]
    if memory is None:
        from granplate.setup.plate_cost import physical_memory

        memory = MEMORY_SHARE * physical_memory()
    memo = None
    if cache:
        memo = (
            store.key(STORE_KIND, cache_payload(sd, material, surface, components), SOLID_FORMAT),
            str(store.cache_directory()),
        )
        built = _BUILT.pop(memo, None)
        if built is not None:
            check_fits(built.cost, memory, seconds, list(sd.elements) if sd.mesh is None else sd.mesh)
            _BUILT[memo] = built  # most recent last
            return built
    built = _build_solid(sd, material, surface, components, cache, memory, seconds)
    if memo is not None:
        _BUILT[memo] = built
        while len(_BUILT) > BUILT_KEPT:
            _BUILT.pop(next(iter(_BUILT)))
    return built


def _build_solid(
    sd: Solid,
    material: Material,
    surface: str | None,
    components: str,
    cache: bool,
    memory: float,
    seconds: float | None,
) -> SolidModel:
    """build_solid without the process's memory."""
    mesh = solid_mesh(sd)
    sbasis = scalar_basis(mesh, sd.element)
    nodes = node_coordinates(sbasis)
    n_full = 3 * nodes.shape[0]
    fixed = fixed_dofs(sbasis, mesh, sd.clamped, sd.rollers)
    dofs = free_dofs(n_full, fixed)
    free = fixed.size == 0
    surface_full = np.zeros(0, dtype=np.int64)
    if surface is not None:
        cols = ["xyz".index(c) for c in components]
        surface_full = face_node_dofs(sbasis, mesh, surface, "surface")[:, cols].ravel()
    surface_dofs = reduced_index(dofs, surface_full)
    surface_dofs = surface_dofs[surface_dofs >= 0]
    xyz = nodes[dofs // 3]
    cost = solid_cost(sd, material, len(dofs), xyz, len(surface_dofs))
    check_fits(cost, memory, seconds, list(sd.elements) if sd.mesh is None else sd.mesh)

    def compute() -> dict:
        K = reduced(solid_stiffness(sbasis, mesh, sd.element, material, sd.rigid_patches), dofs)
        M = reduced(mass_matrix(sbasis, material.rho), dofs)
        k = window_size(cost.n_modes, len(dofs), bool(sd.clamped))
        max_omega = 2.0 * np.pi * sd.max_frequency
        plan = window_plan(xyz.max(axis=0) - xyz.min(axis=0), material, max_omega, k)
        omega, Phi, resid = modes_and_residual(K, M, max_omega, xyz, nodes, free, surface_dofs, k, plan)
        return {"omega": omega, "Phi": Phi, "dofs": dofs, "surface_dofs": surface_dofs, "resid": resid}

    payload = cache_payload(sd, material, surface, components) if cache else None
    arrays = _stored_or_computed(payload, compute)
    faces = {name: face_nodes(sbasis, mesh, name, "plate") for name in face_names(mesh)}
    return SolidModel(
        nodes=nodes,
        dofs=arrays["dofs"],
        omega=arrays["omega"],
        Phi=arrays["Phi"],
        surface_dofs=arrays["surface_dofs"],
        resid=arrays["resid"],
        faces=faces,
        element=sd.element,
        material=material,
        free=free,
        cost=cost,
        mesh=mesh,
        basis=sbasis,
        arrays_key=store.key(STORE_KIND, payload, SOLID_FORMAT) if payload is not None else "",
        rigid_patches=tuple(sd.rigid_patches),
    )

"""The elastic body's fields after a run in space (dimension = 3): displacement, von Mises
stress, the ball-averaged von Mises stress, at every output time, and snapshots.

The body's displacement at output time t, on the reduced (free) dofs [m]:

    u(t) = Phi q(t) + u_s(t),   u_s = G f - Phi_e diag(1/omega_e^2) Phi_e^T f,

q (n_modes,) the modal coordinates [kg^1/2 m], f(t) the nodal forces of the contact forces
on the body (`solid.loads.nodal_force_history`: each granule's force spread over its face's
nodes by the face's shape functions at its contact point), G the static flexibility K^-1
of a held body or the inertia-relief flexibility of a free one (`SolidModel._flexibility`,
one factorisation), Phi_e, omega_e the kept elastic modes: u_s is the static residual of
the modes the truncation drops. The full route evaluates it exactly at every output time
where a contact force acts (no bound, no skipped time; summary_only below skips the
blocks of times that provably cannot hold the run's largest value), as

    u = Phi q_eff + G f,   q_eff = q - diag(1/omega_e^2) Phi_e^T f   (rigid modes: q),

with G f from one of two routes, whichever solves fewer systems: G's columns at the dofs
the run loads (those with a nodal force at some output time), solved once and multiplied
by each time's forces, or one multi-right-hand-side solve per block of times (the loaded
times only). The fixed dofs' displacement is 0.

Per output time (`time`): `max_displacement`, the largest |u| over the nodes [m] (a free
body's rigid-body motion, its zero-frequency modes, included);
`max_von_mises`, the largest von Mises stress over the quadrature points of every element
[Pa] (`solid.stress`: the strains from the vector basis' strain operator, sigma = D eps);
`max_von_mises_ball`, the largest mean of the von Mises stress over a ball of radius
`ball_radius` about each point of the body's surface (`stress.surface_centres`, the
boundary nodes), cut by the body, partial cells by a linear ramp (`stress.ball_operator`):
the 3D analogue of the plate's disc average. At the field times (every field_stride-th
output time and the last, `field_time`): the nodal displacement `body_ux/uy/uz`
(field_time, body_node) [m] and the largest von Mises stress in each element
`body_von_mises` (field_time, body_element) [Pa], with the nodes' coordinates
`body_node_x/y/z` and the elements' nodes `body_element_nodes` in VTK's order
(`solid.vtk_cells`; its attribute `cell_type` names meshio's cell type).

Blocks of output times bound the memory (BLOCK_BYTES of strains and stresses at a time).

summary_only keeps the three maxima, exact in the blocks of output times that can hold the
run's largest value and NaN in the others (as the plate's `plate.peaks`): the fields are
linear in the coordinates c = (q_eff, the nodal forces at the loaded dofs), each maximum a
seminorm of c, so max(t) <= max(r) + sum_i |c_i(t) - c_i(r)| peak_i from a reference time
r (every REFERENCE_STRIDE-th output time, evaluated), peak_i the maximum of unit
coordinate i's field; a block is evaluated while its bound exceeds the largest value found.
The blocks are the full route's, so the values are the same bits and the largest over the
run (nanmax) is the full route's. Where a solve per time is the cheaper route (no G
columns), or modes near the output interval's Nyquist frequency loosen the bounds, every
block is evaluated.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
import scipy.sparse as sp
import xarray as xr

from granplate.plate.peaks import BOUND_MARGIN, largest_bound_first
from granplate.solid.factor import one_blas_thread
from granplate.solid.fe import vector_basis
from granplate.solid.loads import nodal_force_history
from granplate.solid.stress import ball_operator, elasticity_matrix, strain_operator, surface_centres, von_mises
from granplate.solid.surface import Surface, boundary_surface
from granplate.solid.vtk_cells import MESHIO_CELLS, vtk_connectivity

#: Bytes of strains, stresses and displacements one block of output times may hold.
BLOCK_BYTES = 96 * 2**20
#: Bytes the static responses to unit loads at the loaded dofs may hold (else: a solve per time).
UNIT_BYTES = 256 * 2**20
#: Unit loads solved per call.
UNIT_CHUNK = 64

#: name -> (units, description) of the body's variables.
BODY_VARIABLES: dict[str, tuple[str, str]] = {
    "max_von_mises": (
        "Pa",
        "largest von Mises stress over the body's quadrature points (modes and the static residual of the contact forces)",
    ),
    "max_von_mises_ball": (
        "Pa",
        "largest mean von Mises stress over a ball of radius ball_radius about a point of the body's surface, cut by the body",
    ),
    "max_displacement": (
        "m",
        "largest displacement magnitude over the body's nodes (modes, a free body's rigid-body motion included, and the static residual)",
    ),
    "body_ux": ("m", "body nodal displacement, x (at field_time)"),
    "body_uy": ("m", "body nodal displacement, y (at field_time)"),
    "body_uz": ("m", "body nodal displacement, z (at field_time)"),
    "body_von_mises": ("Pa", "largest von Mises stress over each element's quadrature points (at field_time)"),
}
#: What summary_only keeps.
BODY_SUMMARY = ("max_von_mises", "max_von_mises_ball", "max_displacement")


@dataclass(frozen=True)
class BodyOperators:
    """What evaluating the body's fields needs, built once per solid and radius: the
    boundary faces, the strain operator (6 n_points, 3 n_nodes), D [Pa], the ball
    operator (n_centres, n_points), the elastic modes' mask."""

    surface: Surface
    strain: sp.csr_matrix
    D: np.ndarray
    ball: sp.csr_matrix
    elastic: np.ndarray
    n_qp: int
    radius: float


#: Operators built in this process, most recent last: (the solid's run-store key, ball
#: radius) -> BodyOperators (a stored solid's runs share them: a study's designs, repeats).
_BUILT: dict[tuple[str, float], BodyOperators] = {}
#: How many operators a process keeps.
BUILT_KEPT = 2


def body_operators(solid, ball_radius: float, surface: Surface | None = None) -> BodyOperators:
    """The operators of `body_data` for a built solid (SolidModel); a stored solid's (its
    arrays_key) kept in this process for the next run of the same solid and radius."""
    memo = (solid.arrays_key, float(ball_radius)) if solid.arrays_key and surface is None else None
    if memo is not None and memo in _BUILT:
        _BUILT[memo] = _BUILT.pop(memo)  # most recent last
        return _BUILT[memo]
    vb = vector_basis(solid.mesh, solid.element)
    ops = BodyOperators(
        surface=boundary_surface(vb) if surface is None else surface,
        strain=strain_operator(vb),
        D=elasticity_matrix(solid.material.E, solid.material.nu),
        ball=ball_operator(solid.basis, surface_centres(solid.basis), ball_radius),
        elastic=solid.omega > 0.0,
        n_qp=int(solid.basis.dx.shape[1]),
        radius=float(ball_radius),
    )
    if memo is not None:
        _BUILT[memo] = ops
        while len(_BUILT) > BUILT_KEPT:
            _BUILT.pop(next(iter(_BUILT)))
    return ops


def field_indices(n: int, stride: int) -> np.ndarray:
    """The output indices of the field snapshots: every stride-th of n, and the last."""
    idx = np.arange(0, n, max(int(stride), 1))
    return np.append(idx, n - 1) if n and idx[-1] != n - 1 else idx


def loaded_dofs(forces: Callable[[slice], sp.csr_matrix], n_t: int, block: int) -> tuple[np.ndarray, int]:
    """(the reduced dofs with a nodal force at some output time, the number of output times
    with any), from forces(rows) (b, n_red) [N] a block of times at a time."""
    dofs, n_loaded = [], 0
    for start in range(0, n_t, block):
        F = forces(slice(start, min(start + block, n_t)))
        dofs.append(np.unique(F.indices))
        n_loaded += int(np.sum(np.diff(F.indptr) > 0))
    return (np.unique(np.concatenate(dofs)) if dofs else np.zeros(0, np.int64)), n_loaded


class StaticPart:
    """x = G f [m] for the nodal forces of a block of times, by the cheaper route (module
    docstring): G's columns at the loaded dofs, or one solve per loaded time."""

    def __init__(self, solid, dofs: np.ndarray, n_loaded_times: int):
        with one_blas_thread():
            self.solve = solid._flexibility
        self.n = len(solid.dofs)
        self.dofs = dofs
        self.columns = None
        if 0 < len(dofs) <= n_loaded_times and len(dofs) * self.n * 8 <= UNIT_BYTES:
            self.columns = np.empty((self.n, len(dofs)))
            for start in range(0, len(dofs), UNIT_CHUNK):
                cols = dofs[start : start + UNIT_CHUNK]
                f = np.zeros((self.n, len(cols)))
                f[cols, np.arange(len(cols))] = 1.0
                with one_blas_thread():  # SuperLU's small blocks (solid.factor)
                    self.columns[:, start : start + len(cols)] = self.solve(f)

    def __call__(self, F: sp.csr_matrix) -> np.ndarray:
        """(n_red, n_t) G f of forces F (n_t, n_red) [N]."""
        out = np.zeros((self.n, F.shape[0]))
        if F.nnz == 0:
            return out
        if self.columns is not None:
            return self.columns @ F[:, self.dofs].T.toarray()
        rows = np.flatnonzero(np.diff(F.indptr))
        with one_blas_thread():
            out[:, rows] = self.solve(F[rows].T.toarray())
        return out


def block_size(n_points: int, n_full: int) -> int:
    """Output times per block: BLOCK_BYTES over the bytes one time needs (strains,
    stresses and von Mises at the quadrature points, the displacements)."""
    per_time = 8 * (13 * n_points + 3 * n_full)
    return int(np.clip(BLOCK_BYTES // per_time, 1, 512))


def _var(name: str, dims, data) -> xr.DataArray:
    units, desc = BODY_VARIABLES[name]
    return xr.DataArray(data, dims=dims, attrs={"units": units, "long_name": desc})


#: Output times between the references the summary's bounds start from.
REFERENCE_STRIDE = 8
#: Output times per chunk of the bounds.
BOUND_CHUNK = 4096
#: Unit fields evaluated per pass when the unit peaks are computed.
UNIT_BATCH = 32


def coordinates(
    q: np.ndarray, forces: Callable, phi_e: np.ndarray, ops: BodyOperators, static: StaticPart, block: int
) -> np.ndarray:
    """(n_t, n_modes + |S|): each output time's coordinates c in which the body's fields are
    linear, u = [Phi, G_S] c: the effective modal coordinates q_eff and the nodal forces at
    the loaded dofs S [N] (G's columns there: `StaticPart.columns`)."""
    n_t = len(q)
    n_s = len(static.dofs) if static.columns is not None else 0
    c = np.zeros((n_t, q.shape[1] + n_s))
    for start in range(0, n_t, block):
        rows = slice(start, min(start + block, n_t))
        F = forces(rows)
        c[rows, : q.shape[1]] = q[rows]
        c[rows, np.flatnonzero(ops.elastic)] -= np.asarray(F @ phi_e)
        if n_s:
            c[rows, q.shape[1] :] = F[:, static.dofs].toarray()
    return c


def unit_peaks(solid, ops: BodyOperators, static: StaticPart, maxima: Callable) -> np.ndarray:
    """(n_modes + |S|, 3): the three maxima of each unit coordinate's field (a mode's shape,
    G's column at a loaded dof): each maximum is a seminorm of the coordinates, so that
    max(t) <= max(r) + sum_i |c_i(t) - c_i(r)| peak_i (the triangle inequality)."""
    shapes = solid.Phi if static.columns is None else np.hstack([solid.Phi, static.columns])
    n_nodes = solid.nodes.shape[0]
    out = np.empty((shapes.shape[1], 3))
    for start in range(0, shapes.shape[1], UNIT_BATCH):
        cols = shapes[:, start : start + UNIT_BATCH]
        u = np.zeros((3 * n_nodes, cols.shape[1]))
        u[solid.dofs] = cols
        vm = von_mises(ops.D @ (ops.strain @ u).reshape(6, -1)).reshape(-1, cols.shape[1])
        out[start : start + cols.shape[1]] = maxima(u.reshape(n_nodes, 3, -1), vm)
    return out


def bounded_maxima(n_t: int, block: int, exact: Callable, c: np.ndarray, peaks: np.ndarray) -> np.ndarray:
    """(n_t, 3): the exact maxima (exact(rows) -> (b, 3)) in the blocks of output times that
    can hold the run's largest value, NaN in the others.

    The maxima are evaluated at every REFERENCE_STRIDE-th output time (and the last); each
    time is bounded from its nearer reference r by max(r) + sum_i |c_i(t) - c_i(r)| peak_i
    (`unit_peaks`); blocks are evaluated largest bound first while a bound exceeds the
    largest value found (or the largest reference value, less BOUND_MARGIN). The blocks are
    the exact route's, so the values are the same bits."""
    out = np.full((n_t, 3), np.nan)
    if n_t == 0:
        return out
    refs = np.arange(0, n_t, REFERENCE_STRIDE)
    if refs[-1] != n_t - 1:
        refs = np.append(refs, n_t - 1)
    ref_values = np.vstack([exact(refs[k : k + block]) for k in range(0, len(refs), block)])
    at = np.searchsorted(refs, np.arange(n_t)).clip(0, len(refs) - 1)
    bound = np.full((n_t, 3), np.inf)
    for lo in range(0, n_t, BOUND_CHUNK):  # (in chunks of times: bounded memory)
        rows = slice(lo, min(lo + BOUND_CHUNK, n_t))
        for r in (at[rows], np.maximum(at[rows] - 1, 0)):  # the references on either side
            bound[rows] = np.minimum(bound[rows], ref_values[r] + np.abs(c[rows] - c[refs[r]]) @ peaks)
    starts = np.arange(0, n_t, block)
    upper = np.maximum.reduceat(bound * (1.0 + BOUND_MARGIN), starts, axis=0)  # (n_blocks, 3)
    best = ref_values.max(axis=0) * (1.0 - BOUND_MARGIN)
    scale = np.maximum(upper.max(axis=0), np.finfo(float).tiny)
    done = np.zeros(len(starts), dtype=bool)
    if not np.any(upper > best):  # every bound at the floor (at rest): one block still gives the maxima
        best = np.full(3, -np.inf)

    def evaluate(k: int) -> np.ndarray:
        rows = slice(starts[k], min(starts[k] + block, n_t))
        out[rows] = exact(rows)
        return out[rows].max(axis=0)

    largest_bound_first(upper, best, done, scale, evaluate)
    return out


def fields_in_blocks(n_t: int, B: int, evaluate, maxima, fields: np.ndarray, sizes: tuple, should_stop):
    """The body's fields over the output times, B at a time: each time's maxima (von Mises,
    ball-averaged von Mises [Pa], displacement [m]) and, at the snapshot times `fields`, the
    nodal displacements (n_fields, n_nodes, 3) and each element's largest von Mises
    (n_fields, n_elem); evaluate, maxima: `body_data`'s; sizes: (n_nodes, n_elem, n_qp);
    should_stop polled after each block. Returns ((three maxima (n_t,)), (the two
    snapshot arrays), how many output times were computed)."""
    n_nodes, n_elem, n_qp = sizes
    vm_max, ball_max, u_max = np.zeros(n_t), np.zeros(n_t), np.zeros(n_t)
    u_field = np.zeros((len(fields), n_nodes, 3))
    vm_field = np.zeros((len(fields), n_elem))
    done = 0
    for start in range(0, n_t, B):
        rows = slice(start, min(start + B, n_t))
        nodal, vm = evaluate(rows)
        vm_max[rows], ball_max[rows], u_max[rows] = maxima(nodal, vm).T
        snaps = np.flatnonzero((fields >= rows.start) & (fields < rows.stop))
        if len(snaps):
            k = fields[snaps] - rows.start
            u_field[snaps] = np.moveaxis(nodal[:, :, k], -1, 0)
            vm_field[snaps] = vm[:, k].reshape(n_elem, n_qp, len(k)).max(axis=1).T
        done = rows.stop
        if should_stop is not None and done < n_t and should_stop():
            break
    return (vm_max, ball_max, u_max), (u_field, vm_field), done


def body_coordinates(solid, field_times: np.ndarray) -> dict:
    """The body's coordinates for the Dataset: the snapshots' times [s], the nodes'
    positions [m] and the elements' nodes in VTK order (name -> (dims, values, attrs))."""
    coords = {
        "field_time": (
            "field_time",
            field_times,
            {"units": "s", "long_name": "time of the body field snapshots"},
        )
    }
    for c, axis in enumerate("xyz"):
        coords[f"body_node_{axis}"] = (
            "body_node",
            solid.nodes[:, c].copy(),
            {"units": "m", "long_name": f"body node {axis}"},
        )
    coords["body_element_nodes"] = (
        ("body_element", "body_element_node"),
        vtk_connectivity(solid.basis, solid.element),
        {
            "long_name": f"body element nodes in VTK order (meshio cell type {MESHIO_CELLS[solid.element]})",
            "cell_type": MESHIO_CELLS[solid.element],
        },
    )
    return coords


def checked_inputs(solid, q, field_stride: int, contact_face, contact_xi, contact_force):
    """`body_data`'s modal coordinates and contacts as arrays of their shapes (q (n_t,
    n_modes), face (n_t, n_g), xi (n_t, n_g, 2), force (n_t, n_g, 3)); a ValueError for a
    q of another shape or a field_stride below 1."""
    q = np.asarray(q, float)
    n_t = len(q)
    if q.shape != (n_t, solid.n_modes):
        raise ValueError(f"q must be (n_t, {solid.n_modes}), not {q.shape}")
    if int(field_stride) < 1:
        raise ValueError(f"field_stride must be a positive integer, not {field_stride}")
    face = np.asarray(contact_face, np.int64).reshape(n_t, -1)
    n_g = face.shape[1]
    xi = np.asarray(contact_xi, float).reshape(n_t, n_g, 2)
    force = np.asarray(contact_force, float).reshape(n_t, n_g, 3)
    return q, face, xi, force


def body_data(
    solid,
    q: np.ndarray,
    qd: np.ndarray,
    times: np.ndarray,
    contact_face: np.ndarray,
    contact_xi: np.ndarray,
    contact_force: np.ndarray,
    field_stride: int,
    ball_radius: float,
    summary_only: bool = False,
    should_stop: Callable[[], bool] | None = None,
    operators: BodyOperators | None = None,
    nodal_forces: Callable | None = None,
) -> tuple[dict[str, xr.DataArray], dict]:
    """The body's data variables and coordinates for the result Dataset (module docstring).

    solid: the built solid (solid.build.SolidModel); q, qd (n_t, n_modes): the modal
    coordinates [kg^1/2 m] and velocities [kg^1/2 m/s] (qd is not needed by these fields);
    times (n_t,) [s]; contact_face (n_t, n_g) int: the boundary face
    (`surface.boundary_surface` of the solid's vector basis) each granule touches, -1 for
    none; contact_xi (n_t, n_g, 2): the reference point on it; contact_force (n_t, n_g, 3)
    [N]: the force on the body there; field_stride: output times between snapshots;
    ball_radius [m]; summary_only: only the per-time maxima (BODY_SUMMARY), exact where
    they can reach the run's largest value, NaN elsewhere (module docstring), no
    coordinates, should_stop not polled; should_stop: polled after each block of times: when it says yes, the
    variables cover the output times computed so far (their `time` length says how many);
    operators: `body_operators` built before (default: built here); nodal_forces: rows ->
    (b, n_red) [N] sparse, the nodal forces at those output times (default: each contact
    force at its point, `solid.loads.nodal_force_history`; a run's disc patches spread
    them over their nodes, results.body_contacts.patch_forces).

    Returns (data variables, coordinates as name -> (dims, values, attrs))."""
    q, face, xi, force = checked_inputs(solid, q, field_stride, contact_face, contact_xi, contact_force)
    n_t = len(q)
    ops = body_operators(solid, ball_radius) if operators is None else operators
    if ops.radius != float(ball_radius):
        raise ValueError(f"the operators' ball radius {ops.radius} m is not ball_radius = {ball_radius} m")
    n_nodes = solid.nodes.shape[0]
    n_full = 3 * n_nodes
    n_points = ops.strain.shape[0] // 6
    n_elem = n_points // ops.n_qp
    phi_e = solid.Phi[:, ops.elastic] / solid.omega[ops.elastic] ** 2  # (n_red, n_elastic) [m/N]
    B = block_size(n_points, n_full)

    def forces(rows) -> sp.csr_matrix:  # (b, n_red) [N] at output times rows (a slice or indices)
        if nodal_forces is not None:
            return nodal_forces(rows)
        return nodal_force_history(ops.surface, solid.dofs, n_full, face[rows], xi[rows], force[rows])

    loaded, n_loaded = loaded_dofs(forces, n_t, B)
    static = StaticPart(solid, loaded, n_loaded)
    fields = np.zeros(0, np.int64) if summary_only else field_indices(n_t, field_stride)

    def evaluate(rows) -> tuple[np.ndarray, np.ndarray]:
        """(nodal displacements (n_nodes, 3, b) [m], von Mises (n_points, b) [Pa]) at the
        output times rows (a slice or indices)."""
        F = forces(rows)
        q_eff = q[rows].copy()
        q_eff[:, ops.elastic] -= np.asarray(F @ phi_e)
        u_red = solid.Phi @ q_eff.T + static(F)  # (n_red, b)
        u = np.zeros((n_full, u_red.shape[1]))
        u[solid.dofs] = u_red
        eps = (ops.strain @ u).reshape(6, -1)  # (6, n_points b): component, point, time
        return u.reshape(n_nodes, 3, -1), von_mises(ops.D @ eps).reshape(n_points, -1)

    def maxima(nodal: np.ndarray, vm: np.ndarray) -> np.ndarray:
        """(b, 3): the largest von Mises, ball-averaged von Mises [Pa] and displacement [m]."""
        ball = (ops.ball @ vm).max(axis=0) if ops.ball.shape[0] else np.zeros(vm.shape[1])
        return np.column_stack([vm.max(axis=0), ball, np.sqrt(np.einsum("nck,nck->nk", nodal, nodal)).max(axis=0)])

    if summary_only and (static.columns is not None or len(loaded) == 0):
        every = bounded_maxima(
            n_t,
            B,
            lambda rows: maxima(*evaluate(rows)),
            coordinates(q, forces, phi_e, ops, static, B),
            unit_peaks(solid, ops, static, maxima),
        )
        vm_max, ball_max, u_max = every[:, 0], every[:, 1], every[:, 2]
        done = n_t
    else:
        (vm_max, ball_max, u_max), (u_field, vm_field), done = fields_in_blocks(
            n_t, B, evaluate, maxima, fields, (n_nodes, n_elem, ops.n_qp), should_stop
        )
    kept = int(np.sum(fields < done))
    data = {
        "max_von_mises": _var("max_von_mises", ("time",), vm_max[:done]),
        "max_von_mises_ball": _var("max_von_mises_ball", ("time",), ball_max[:done]),
        "max_displacement": _var("max_displacement", ("time",), u_max[:done]),
    }
    data["max_von_mises_ball"].attrs["ball_radius"] = float(ball_radius)
    if summary_only:
        return data, {}
    for c, axis in enumerate("xyz"):
        data[f"body_u{axis}"] = _var(f"body_u{axis}", ("field_time", "body_node"), u_field[:kept, :, c].copy())
    data["body_von_mises"] = _var("body_von_mises", ("field_time", "body_element"), vm_field[:kept])
    coords = body_coordinates(solid, np.asarray(times, float)[fields[:kept]])
    return data, coords

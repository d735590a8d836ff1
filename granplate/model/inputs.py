"""The time loop's inputs: flat arrays of the granular medium, the plate's modal model
and the scalar settings, as numba-friendly named tuples built once by `build_model`.

Coefficient columns of pair_coef, wall_coef and pc_coef are named in
granplate.physics.contact (COEF_A, COEF_C, COEF_MU, COEF_KS, COEF_DY).
"""

from __future__ import annotations

from typing import NamedTuple

import math

import numpy as np

from granplate.physics.contact import N_COEF
from granplate.physics.drives import N_PAR
from granplate.setup.validate import SCHEMES

#: the coupling schemes (setup.validate.SCHEMES), numbered in this order (Config.scheme);
#: each has a module in granplate.solver.schemes registered under the same name.
SCHEME_NAMES = SCHEMES
SCHEME_PAPER, SCHEME_IMPLICIT, SCHEME_VERLET = 0, 1, 2


def scheme_number(name: str) -> int:
    """Config.scheme of the scheme called `name` (one of SCHEME_NAMES)."""
    if name not in SCHEME_NAMES:
        raise ValueError(f"solver.scheme = {name!r}: allowed {', '.join(SCHEME_NAMES)}")
    return SCHEME_NAMES.index(name)


#: state columns per granule by dimension: the plane's (x, y, theta, vx, vy, omega) and
#: space's (x, y, z, vx, vy, vz, wx, wy, wz)
STATE_COLUMNS = {2: 6, 3: 9}

#: columns of the contact histories pair_hist, wall_hist, pc_hist (Granular): the largest
#: overlap so far delta_max [m] (the elastic-plastic law's history, docs/model.md section
#: 3.6; for every law, its largest Hertz peak pressure), the time it was reached [s], and
#: the overlap at the end of the last trial step [m] (taken into delta_max when the step is
#: accepted), and the rate factor Y(rate) / Y [-] that fixed the yield strength of a contact
#: under the law "johnson" (docs/model.md section 3.10: 0 while unset, 1 rate-free).
#: Then Mindlin's tangential law (docs/model.md section 3.16): the elastic tangential
#: displacement xi (3 components) [m], the contact radius a [m] and the tangential force on
#: the first body (3) [N] of the last accepted step, and the same at the end of the last
#: trial step (taken in when the step is accepted; N_MINDLIN columns each).
HIST_MAX, HIST_TIME, HIST_END, HIST_RATE = 0, 1, 2, 3
HIST_XI, HIST_A, HIST_F = 4, 7, 8
N_MINDLIN = 7
HIST_XI_END, HIST_A_END, HIST_F_END = 11, 14, 15
N_HIST = 18
#: the columns of a Mindlin contact's row under velocity Verlet (HIST_MAX to HIST_F): every
#: step is accepted, so the force pass moves the history on in place and the trial columns
#: (HIST_XI_END to HIST_F_END) are not kept (solver.mindlin_history.trial_column; a row of
#: N_HIST columns, a scheme that may retry a step, keeps the trial apart until it commits).
N_HIST_STEP = HIST_XI_END
#: the columns a contact's history row has in a run whose tangential law keeps no history
#: (the normal law's, HIST_MAX to HIST_RATE): a row of 4 numbers, not 18, streamed by every
#: force pass and history commit (docs/benchmarks.md, "Every core in one run"). Mindlin's
#: columns are read only where the contact's law keeps a history (laws.keeps_history).
N_HIST_NORMAL = 4


#: columns of Granular.drive_now, each drive's state at the last force pass: its
#: displacement s [m], velocity v [m/s] and acceleration a [m/s^2] along its direction (a
#: force drive on a granule: its force in DR_A), the force F [N] the drive applies on its
#: body along the direction, its power F v [W], the power of the contact damping forces on
#: the granules at the wall's velocity [W] (a wall's), and a wall's displacement when the
#: contact list was last built [m]; a wall's: the damping part of the contacts' force
#: counted as F is [N]; a piston's (a force-driven wall, solver.drives): the contacts' force
#: against its drive R [N] (its acceleration DR_A = (F - R) / M) and its velocity after the
#: step's first half kick [m/s]. A piston's s and v are its state (the scheme integrates them).
#: Under the RK4 schemes (paper, implicit) a piston's s, v and a at the last accepted step
#: (DR_SC, DR_VC, DR_AC; DR_S, DR_V, DR_A are then the trial step's) and the sums of its
#: RK4 stages' velocities and accelerations (DR_KS, DR_KV).
DR_S, DR_V, DR_A, DR_F, DR_P, DR_PD, DR_REF, DR_FD, DR_R, DR_VH = range(10)
DR_SC, DR_VC, DR_AC, DR_KS, DR_KV = range(10, 15)
N_DRIVE = 15


def no_history(n: int, columns: int = N_HIST) -> np.ndarray:
    """A zero history for n contacts ((n, columns), columns HIST_*: N_HIST, or
    N_HIST_NORMAL in a run without a tangential law with history, `history_columns`)."""
    return np.zeros((n, columns))


def history_columns(history: bool, in_place: bool = False) -> int:
    """The columns of a run's contact histories: where its tangential law keeps a history
    (Mindlin's) N_HIST, or N_HIST_STEP where the scheme moves it on in place (`in_place`:
    velocity Verlet); else N_HIST_NORMAL."""
    if not history:
        return N_HIST_NORMAL
    return N_HIST_STEP if in_place else N_HIST


class Granular(NamedTuple):
    """Flat arrays of the granular medium and its contacts (SI units).

    mass, inertia, radius: (ng,); pair_ij: (np, 2) granule indices (the pairs that may
    touch, sorted); pair_coef: (np, N_COEF) each pair's coefficient row (physics.contact COEF_*); wall_i:
    (nw,); wall_geo: (nw, 3) [nx, ny, offset]; wall_coef: (nw, 4); wall_w: (nw,) index of
    the wall in the scenario; pc_i: (nk,) granule of each plate contact;
    pc_x: (nk,) x of the plate edge the contact's overlap is measured from (the
    undeformed face; a patch contact's is shifted as its patch moves, docs/model.md
    section 3.5); pc_coef: (nk, 4); shock_force, shock_torque: (ng,) load resultants per
    unit q0 [m, m^2]; pc_patch: (nk,) int, 1 for a patch contact (its plate rows move
    with the granule, docs/model.md section 3.5), 0 for a rigid layer; empty while
    there is no patch contact (the loop then skips them at no cost); pair_hist,
    wall_hist, pc_hist: (np, H), (nw, H), (nk, H) each contact's history (columns HIST_*;
    H = N_HIST, or N_HIST_NORMAL without a tangential law with history: `history_columns`),
    this run's own (the loop updates them in place).

    Gravity and drives (docs/model.md section 3.11; empty: none): gravity (d,) [m/s^2];
    per drive: drive_target (nD,) int, the granule i >= 0 or the wall -1 - w it drives;
    drive_kind, drive_prof (nD,) int (physics.drives KIND_*, PROFILE_*); drive_dir (nD,
    d) its unit direction; drive_par (nD, N_PAR) its profile's parameters (and a
    force-driven wall's mass, physics.drives PAR_*); drive_tab (nD,
    L, 3) and drive_tlen (nD,) int its table (physics.drives TAB_*); drive_x0 (nD, d) its
    granule's centre at t = 0 [m]; drive_now (nD, N_DRIVE) its state at the last force
    pass (columns DR_*, this run's own). wall_drive (n_walls,) int: the drive of each
    scenario wall or -1 (empty: no wall is driven); wall_load (n_walls,): the normal force
    each wall received at the last force pass [N] (this run's own).

    The pairs' coefficient kinds (model.relists.with_pair_kinds; empty: not made yet):
    pair_kind (np,) int32, the row of kind_coef (nk, N_COEF) that holds pair p's row
    pair_coef[p], bit for bit (model.coefficients.coefficient_kinds). The pair loop of
    velocity Verlet in space reads them: a few rows that stay in the cache, where a row per
    pair would come from memory at every pass. Made with pair_coef, never changed apart.
    """

    mass: np.ndarray
    inertia: np.ndarray
    radius: np.ndarray
    pair_ij: np.ndarray
    pair_coef: np.ndarray
    wall_i: np.ndarray
    wall_geo: np.ndarray
    wall_coef: np.ndarray
    wall_w: np.ndarray
    pc_i: np.ndarray
    pc_x: np.ndarray
    pc_coef: np.ndarray
    shock_force: np.ndarray
    shock_torque: np.ndarray
    pc_patch: np.ndarray = np.zeros(0, np.int64)
    pair_hist: np.ndarray = no_history(0)
    wall_hist: np.ndarray = no_history(0)
    pc_hist: np.ndarray = no_history(0)
    gravity: np.ndarray = np.zeros(0)
    drive_target: np.ndarray = np.zeros(0, np.int64)
    drive_kind: np.ndarray = np.zeros(0, np.int64)
    drive_prof: np.ndarray = np.zeros(0, np.int64)
    drive_dir: np.ndarray = np.zeros((0, 2))
    drive_par: np.ndarray = np.zeros((0, N_PAR))
    drive_tab: np.ndarray = np.zeros((0, 1, 3))
    drive_tlen: np.ndarray = np.zeros(0, np.int64)
    drive_x0: np.ndarray = np.zeros((0, 2))
    drive_now: np.ndarray = np.zeros((0, N_DRIVE))
    wall_drive: np.ndarray = np.zeros(0, np.int64)
    wall_load: np.ndarray = np.zeros(0)
    pair_kind: np.ndarray = np.zeros(0, np.int32)
    kind_coef: np.ndarray = np.zeros((0, N_COEF))


#: Flat arrays of a granular medium in space (docs/model.md section 3.7), with the fields of
#: `Granular` (so the loop reads both alike; solver.dimension tells them apart by type):
#: wall_geo (nw, 4) [nx, ny, nz, offset] with the unit outward normal; shock_force (ng, 3)
#: [-]: each granule's share of the load's direction, per unit of the total force
#: (load.kind = "force"); shock_torque (ng, 3) zeros; no plate contacts (pc_* empty).
Granular3 = NamedTuple("Granular3", list(Granular.__annotations__.items()))
Granular3.__new__.__defaults__ = Granular.__new__.__defaults__
Granular3.__doc__ = "Flat arrays of a granular medium in space, with the fields of Granular (model.inputs)."


class PlateArrays(NamedTuple):
    """The plate in mass-normalised modal coordinates.

    omega2: (nm,) squared circular frequencies [rad^2/s^2]; phi_d: (nd, nm) mode shapes
    at the driving DOFs (x, y of each contact); load_modal: (nm,) modal edge load per
    unit q0 (zeros when the shock is on the granules); resid: (nd, nd) residual static
    compliance R [m/N] of a truncated basis (docs/model.md section 4.5), (0, 0) when
    every mode is kept; face_y: (n_face,) heights of the face nodes [m] and phi_face:
    (2 n_face, nm) the mode shapes at their dofs, which patch contacts average
    (docs/model.md section 3.5; empty without patch contacts); resid_face: (2 n_face,
    2 n_face) the truncated basis' residual compliance between the face's dofs [m/N],
    whose weighted averages w^T R_face w are the patch contacts' rows of resid (docs/model.md
    section 4.5; (0, 0) with every mode kept or without patch contacts).
    """

    omega2: np.ndarray
    phi_d: np.ndarray
    load_modal: np.ndarray
    resid: np.ndarray = np.zeros((0, 0))
    face_y: np.ndarray = np.zeros(0)
    phi_face: np.ndarray = np.zeros((0, 0))
    resid_face: np.ndarray = np.zeros((0, 0))


class Config(NamedTuple):
    """Scalar settings of the loop (SI units)."""

    q0: float
    duration: float
    clip: bool
    lambda_target: float
    rtol: float
    atol: float
    max_iter: int
    energy_tol: float
    dt_max: float
    dt_min: float
    out_dt: float
    t_end: float
    load_on_plate: bool
    arm_shrink: float = 0.0  # 0: friction arm R (docs/model.md section 3.2); 1: arm to the contact point
    scheme: int = 0  # index into SCHEME_NAMES
    error_tol: float = 1e-3  # implicit scheme: local error target of the step control
    force_floor: float = 0.0  # implicit scheme: smallest force scale of the error estimate [N]
    rebuild_move: float = 0.0  # a granule moving this far [m] since the list was built ends the chunk (0: never)
    overlap_stop: float = math.inf  # an overlap beyond this fraction of the smaller radius stops the run
    plate_x0: float = math.inf  # the plate's undeformed face x [m] (inf: no plate)
    plate_ylo: float = 0.0  # its extent in y [m]
    plate_yhi: float = 0.0
    split_friction: bool = True  # solver.granular_friction = "split" (solver.rk4.rk4_granular_step)
    face_skin: float = 0.0  # > 0: a granule within face_skin R of the face gets a patch contact (0: never)
    patch_width: float = 0.0  # width of a patch contact [m] (plate.rigid_layer_width)
    dimension: int = 2  # 2: the plane (state x, y, theta, vx, vy, omega); 3: space (x, y, z, vx, vy, vz, wx, wy, wz)
    threads: int = 1  # blocks of the velocity-Verlet passes, one per thread (solver.blocks; 1: serial)
    lammps_arms: bool = False  # contact.torque_arm = "lammps": Mindlin's torque at R - delta/2 (pairs), R (walls)
    history_friction: bool = False  # a tangential law with history (Mindlin's): the Verlet force pass runs it
    history_stages: bool = False  # that law under the RK4 schemes: in their stages (solver.mindlin_rk4)
    half_step_damping: bool = False  # solver.verlet_damping = "half_step": Verlet's force pass reads v at t + h/2
    rate_friction: bool = (
        True  # a pair or wall contact may carry a rate law's mu (False: Verlet skips the friction passes' scan)
    )
    energy_span: float = (
        0.0  # implicit scheme: the time [s] its step control spreads energy_tol / 2 over (solver.energy_span)
    )


#: columns of BodyArrays.geo, one row per granule and buffer (docs/model.md section 3.9):
#: the closest point's face coordinates, the centre's signed distance to the undeformed
#: surface [m], the outward unit normal there, the static (elastic) normal force in
#: series with the residual compliance [N], the whole normal force with its damping [N],
#: the damping part of it [N], the effective overlap [m], and 1.0 when the contact is in
#: touch (0.0 otherwise).
#: Then the surface gradient of the normal displacement u_n [-] (the deformed surface's
#: tilt, whose work the granule's force carries: docs/model.md section 3.9).
GEO_XI, GEO_ETA, GEO_DIST, GEO_NX, GEO_NY, GEO_NZ, GEO_NSTAT, GEO_N, GEO_DAMP, GEO_DELTA, GEO_TOUCH = range(11)
GEO_GX, GEO_GY, GEO_GZ = 11, 12, 13
N_GEO = 14


class BodyArrays(NamedTuple):
    """An elastic body in space (docs/model.md section 3.9) as the loop reads it: its
    boundary's quadratic faces, its modes at their nodes, its residual compliance, each
    granule's contact coefficients with it, and (per run) each granule's contact state.

    face_nodes: (n_faces, n_fn, 3) [m] the faces' node coordinates (solid.surface);
    face_snode: (n_faces, n_fn) int each face node's surface node; node_xyz: (n_sn, 3)
    [m] the surface nodes; node_area: (n_sn,) [m^2] each one's share of the surface;
    node_rows: (n_sn, 3) int the row of Phi of its x, y, z dof (-1: fixed); node_resid:
    (n_sn, 3) int the index of that dof in resid (-1: not in the residual set S); grid:
    (1,) [m] the cell size of a grid over the surface nodes, grid_origin (3,) [m],
    grid_shape (3,) int, cell_start (n_cells + 1,) int and cell_nodes (n_sn,) int its
    nodes cell by cell (a disc patch's search); neighbours: (n_faces, k) int faces sharing a corner (-1
    padded); kind: (1,) int the face kind (solid.surface QUAD8, QUAD9, TRI6); phi:
    (n_red, nm) the M-orthonormal modes [kg^-1/2]; omega: (nm,) [rad/s]; resid: (n_s,
    n_s) [m/N] the residual compliance over S ((0, 0): none); box: (2, 3) [m] the lowest
    and highest corner of the body's bounding box; coef: (ng, N_COEF) each granule's
    contact coefficients with the body; load: (nm,) the modal projection Phi^T f of a
    line load on the body's face xmin per unit q0 [N kg^-1/2 per N/m] (zeros: none);
    weight: (nm,) the modal force of the body's own weight Phi^T f_g [N kg^-1/2] (zeros:
    none; model.body_weight).

    The state of one run (new_body_state copies it): face: (2, ng) int each granule's
    closest face in the two buffers (t_n and the trial step's end; the seed of the next
    search); geo: (2, ng, N_GEO); entry, weights: (2, ng, P) each contact's patch as
    entries (face * n_fn + node, weight), count: (2, ng) how many (P = 7 n_fn: the patch
    surface nodes a patch can hold), grad: (ng, P, 3) the weights' gradients in the
    granule's position [1/m] at the last force pass; patch: (1,) the patch radius [m] (0:
    a point); fmodal, fdamp: (2, nm) the contact forces' and their damping parts'
    modal projections Phi^T F [N kg^-1/2]; hist: (ng, N_HIST) each contact's history;
    q, qd, qdp: (nm,) the trial step's modal displacement and velocity and the velocity
    predicted for the force pass; static: (2,) the residual compliance's energy [J];
    active: (ng,) int, and rcol, rcoef: (ng, 3 P), rgrad: (ng, 3 P, 3)
    scratch of the residual solve (each term's dof in S, its weight, its gradient); mrow:
    (nm,) modal scratch of a step (the split friction's unit impulse share,
    solver.body_friction; the modes' rates of Mindlin's pass, solver.body_mindlin).
    """

    face_nodes: np.ndarray
    face_snode: np.ndarray
    node_xyz: np.ndarray
    node_area: np.ndarray
    node_rows: np.ndarray
    node_resid: np.ndarray
    grid: np.ndarray
    grid_origin: np.ndarray
    grid_shape: np.ndarray
    cell_start: np.ndarray
    cell_nodes: np.ndarray
    neighbours: np.ndarray
    kind: np.ndarray
    phi: np.ndarray
    omega: np.ndarray
    resid: np.ndarray
    box: np.ndarray
    coef: np.ndarray
    load: np.ndarray
    weight: np.ndarray
    patch: np.ndarray
    face: np.ndarray
    geo: np.ndarray
    entry: np.ndarray
    weights: np.ndarray
    count: np.ndarray
    grad: np.ndarray
    fmodal: np.ndarray
    fdamp: np.ndarray
    hist: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdp: np.ndarray
    static: np.ndarray
    active: np.ndarray
    rcol: np.ndarray
    rcoef: np.ndarray
    rgrad: np.ndarray
    mrow: np.ndarray


class NoBodyArrays(BodyArrays):
    """The BodyArrays of a run without an elastic body: the same fields, empty, and a type of
    its own, so that the compiled loop picks the code without a body when it compiles
    (`solver.body.by_body`) and never compiles the body's for such a run."""

    __slots__ = ()


def no_body(ng: int, nm: int) -> BodyArrays:
    """The BodyArrays of a run without an elastic body (no faces: the loop skips it), of the
    type NoBodyArrays."""
    z = np.zeros
    i = np.int64
    return NoBodyArrays(
        face_nodes=z((0, 1, 3)),
        face_snode=np.zeros((0, 1), i),
        node_xyz=z((0, 3)),
        node_area=z(0),
        node_rows=np.zeros((0, 3), i),
        node_resid=np.zeros((0, 3), i),
        grid=np.ones(1),
        grid_origin=z(3),
        grid_shape=np.ones(3, i),
        cell_start=np.zeros(2, i),
        cell_nodes=np.zeros(0, i),
        neighbours=np.zeros((0, 1), i),
        kind=np.zeros(1, i),
        phi=z((0, nm)),
        omega=z(nm),
        resid=z((0, 0)),
        box=z((2, 3)),
        coef=z((0, 5)),
        load=z(nm),
        weight=z(nm),
        patch=z(1),
        face=np.zeros((2, 0), i),
        geo=z((2, 0, N_GEO)),
        entry=np.zeros((2, 0, 1), i),
        weights=z((2, 0, 1)),
        count=np.zeros((2, 0), i),
        grad=z((0, 1, 3)),
        fmodal=z((2, nm)),
        fdamp=z((2, nm)),
        hist=no_history(0),
        q=z(nm),
        qd=z(nm),
        qdp=z(nm),
        static=z(2),
        active=np.zeros(0, i),
        rcol=np.zeros((0, 3), i),
        rcoef=z((0, 3)),
        rgrad=z((0, 3, 3)),
        mrow=z(nm),
    )


def new_body_state(b: BodyArrays) -> BodyArrays:
    """b with its per-run state (face onwards) copied, so that a run never writes into the
    model's arrays; the geometry, modes and coefficients are shared."""
    return b._replace(
        face=b.face.copy(),
        geo=b.geo.copy(),
        entry=b.entry.copy(),
        weights=b.weights.copy(),
        count=b.count.copy(),
        grad=b.grad.copy(),
        fmodal=b.fmodal.copy(),
        fdamp=b.fdamp.copy(),
        hist=b.hist.copy(),
        q=b.q.copy(),
        qd=b.qd.copy(),
        qdp=b.qdp.copy(),
        static=b.static.copy(),
        active=b.active.copy(),
        rcol=b.rcol.copy(),
        rcoef=b.rcoef.copy(),
        rgrad=b.rgrad.copy(),
        mrow=b.mrow.copy(),
    )

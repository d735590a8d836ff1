"""The loop's state, shared scratch and output buffers, and the layouts of their small
bookkeeping arrays (named columns). Allocated once per run, updated in place.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from granplate.model.inputs import STATE_COLUMNS  # noqa: F401 - the state's columns per dimension

# clock (float64)
T_NOW, H_LAST, E_IN_MAX, E_ZERO, E_POT, CUSTOM_H, F_SCALE, RES_LAST = 0, 1, 2, 3, 4, 5, 6, 7
# the energy of an elastic body's residual compliance at its contacts [J] (solver.body; part of E_p)
E_STATIC = 8
# the time the trial step ends at, as the clock will read once it is accepted [s] (set
# before each attempt: a scheme whose every step is accepted commits the contacts' largest
# overlaps in its force pass then)
T_TRIAL = 9
N_CLOCK = 10
# count (int64)
C_STEPS, C_LEVEL, C_OUT, C_ITERS, C_RETRIES = 0, 1, 2, 3, 4
# steps taken within 2x of RK4's stability bound on the friction it integrates
# (solver.granular_friction = "rk4" only; the driver then suggests "split")
C_FRICTION_BOUND = 5
N_COUNT = 8
# acc (float64): integrated powers, and the plastic work (docs/model.md eq. P10) booked
# as each contact loaded past its largest overlap
A_SHOCK_G, A_VISC, A_FRIC, A_SHOCK_P, A_PLASTIC = 0, 1, 2, 3, 4
# the work of gravity and of the drives [J] (docs/model.md section 3.11), inputs of eq. (11)
A_GRAVITY, A_DRIVE = 5, 6
N_ACC = 7
# energy output columns
(
    E_SHOCK,
    E_GRAN,
    E_PLATE,
    D_VISC,
    D_FRIC,
    KE_X,
    KE_Y,
    KE_ROT,
    RESID,
    RESID_MAX,
    E_POTG,
    D_PLASTIC,
    KE_Z,
) = range(13)
E_GRAVITY, E_DRIVE = 13, 14
N_ENERGY = 15
# step-statistics output columns
S_STEPS, S_DT_MIN, S_DT_MAX, S_ITERS, S_RETRIES, S_LAM_MAX = range(6)
N_STEPSTAT = 6
# failure record (float64)
ERR_T, ERR_CONTACT, ERR_N, ERR_VT, ERR_LAM, ERR_H, ERR_RESID, ERR_ITER = range(8)
N_ERR = 8
# status codes of `advance`; PAUSED: the chunk's step budget is spent (not an error);
# REBUILD: a granule moved farther than the contact list allows (rebuild it, go on);
# ERR_OVERLAP: an overlap beyond contact.overlap_stop; ERR_PLATE_REACH: a granule without
# a plate contact reached the plate's face; ERR_JUMP: a granule moved more than the
# smallest radius in one step; ERR_MISSED: two bodies overlap that no contact accounts
# for (found by the driver's search when the list is rebuilt or checked); NEW_PLATE: a
# granule without a plate contact came within contact.skin R of the plate's face (the
# driver gives it a patch contact, docs/model.md section 3.5, and goes on)
OK, ERR_NAN, ERR_ENERGY, ERR_NOCONV, ERR_BUFFER, PAUSED = 0, 1, 2, 3, 4, 5
REBUILD, ERR_OVERLAP, ERR_PLATE_REACH, ERR_JUMP, ERR_MISSED, NEW_PLATE = 6, 7, 8, 9, 10, 11
#: partner code of a plate contact in Work.ovl_with (a granule j >= 0, wall w: -1 - w)
PARTNER_PLATE = -(1 << 40)
#: the partner code of a granule's contact with the elastic body in space (the plate's)
PARTNER_BODY = PARTNER_PLATE

#: time steps live on a ladder h_l = dt_max 2^(-l/4), l < N_LEVELS; slot N_LEVELS of the
#: per-level arrays holds an odd step (one that lands on an output time).
LEVEL_RATIO = 2.0**-0.25
N_LEVELS = 200


class State(NamedTuple):
    """Everything at t_n (updated in place by `advance`)."""

    y: np.ndarray  # (ng, 6): x, y, theta, vx, vy, omega
    acc: np.ndarray  # (N_ACC,)
    q: np.ndarray  # (nm,) modal displacement, velocity, acceleration
    qd: np.ndarray
    qdd: np.ndarray
    u: np.ndarray  # (nd,) driving-DOF displacement, velocity, acceleration
    v: np.ndarray
    a: np.ndarray
    force: np.ndarray  # (nd,) interface force on the plate
    force_prev: np.ndarray
    k1: np.ndarray  # (ng, 6) time derivative at t_n
    k0: np.ndarray  # (ng, 6) time derivative at t_n-1
    pforce: np.ndarray  # (nd,) the force the plate moved with over the last step
    p1: np.ndarray  # (5,) shock, viscous, friction, drive, gravity power at t_n
    normal: np.ndarray  # (nk,) |N| at plate contacts
    slip: np.ndarray  # (nk,) tangential slip rate at plate contacts
    clock: np.ndarray
    count: np.ndarray
    err: np.ndarray


class Work(NamedTuple):
    """Scratch every scheme uses: the RK4 stages, the trial step's end values, the
    per-level G(h) and the per-output-interval maxima (allocated once)."""

    ytmp: np.ndarray  # (ng, 6) RK4 stage state
    ynew: np.ndarray  # (ng, 6) granules at the end of the trial step
    k1h: np.ndarray  # (ng, 6) stage-1 derivative when the plate friction is held
    k2: np.ndarray
    k3: np.ndarray
    k4: np.ndarray
    kend: np.ndarray  # (ng, 6) derivative at the end of the trial step
    up: np.ndarray  # (nd,) driving-DOF displacement, velocity of the current RK4 stage
    vp: np.ndarray
    fguess: np.ndarray  # (nd,) the interface forces the plate moves with (the unknowns)
    fbar: np.ndarray  # (nk,) plate-contact friction held over the step
    stage: np.ndarray  # (4, nd) driving-DOF u, v at t + h/2 and u, v at t + h
    fnew: np.ndarray  # (nd,) interface forces at the end of the trial step
    fscratch: np.ndarray
    pend: np.ndarray  # (5,) shock, viscous, friction, drive, gravity power at the end
    dacc: np.ndarray  # (6,) the first three's integrals over the step, the plastic work past the largest
    # overlaps, the work of gravity and of the drives (with their impulses)
    p1h: np.ndarray  # (5,) stage-1 powers when the plate friction is held
    normal_new: np.ndarray  # (nk,) |N| and slip rate at the end of the trial step
    slip_new: np.ndarray
    nscratch: np.ndarray
    sscratch: np.ndarray
    conv_iter: np.ndarray  # (nk,) int: iteration at which each contact converged
    dmode: np.ndarray  # (N_LEVELS + 1, nm) 1/(1 + h^2 omega^2/4) per level
    gmat: np.ndarray  # (N_LEVELS + 1, nd, nd) G(h) per level
    g_ok: np.ndarray  # (N_LEVELS + 1,) int: level computed
    lam_int: np.ndarray  # (nk,) max |lambda| since last output
    it_int: np.ndarray  # (nk,) max iterations since last output
    dt_int: np.ndarray  # (2,) min, max step since last output
    res_int: np.ndarray  # (1,) max |residual| since last output
    yref: np.ndarray  # (ng, 3) granule centres when the contact list was last built (z unused in the plane)
    ovl: np.ndarray  # (ng,) largest overlap / smaller radius seen at each granule's contacts
    ovl_with: np.ndarray  # (ng,) int: its partner (granule j, wall -1 - w, PARTNER_PLATE)
    plate_free: np.ndarray  # (ng,) int: 1 for a granule without a plate contact
    ovl_new: np.ndarray  # (1,) largest overlap / smaller radius at the end of the trial step
    ovl_who: np.ndarray  # (2,) int: its granule and partner (-1, -1: no overlap)
    wface: np.ndarray  # (n_face,) scratch: a patch's nodal weights
    patch_y: np.ndarray  # (nk,) the height [m] each patch contact's weights were computed at
    pweight: np.ndarray  # (nk, n_face) each plate contact's nodal weights on the face (truncated basis)
    prange: np.ndarray  # (nk, 2) int: the first and last face node of each row of pweight
    wflag: np.ndarray  # (threads,) int scratch: each block's flag in the threaded contact watch (solver.contacts)


class Output(NamedTuple):
    """Preallocated output buffers at the output times o * out_dt."""

    target: np.ndarray  # (no,) the output times, set by the caller
    t: np.ndarray  # (no,) the times reached (equal to target)
    y: np.ndarray  # (no, ng, 6)
    energy: np.ndarray  # (no, N_ENERGY)
    q: np.ndarray  # (no, nm)
    qd: np.ndarray  # (no, nm)
    force: np.ndarray  # (no, nk, 2) normal, tangential force on the plate
    slip: np.ndarray  # (no, nk)
    lam: np.ndarray  # (no, nk) max |lambda| over the interval ending here
    iters: np.ndarray  # (no, nk) max iterations to converge over the interval
    stats: np.ndarray  # (no, N_STEPSTAT)
    wall_force: np.ndarray  # (no, n_walls) the normal force each wall receives [N]
    drive: np.ndarray  # (no, n_drives, 2) each drive's force [N] and displacement [m] along its direction
    sensor_target: np.ndarray  # (ns,) the sensors' sample times [s], set by the caller (empty: no sensors)
    sensor_t: np.ndarray  # (ns,) the times reached (equal to sensor_target)
    sensor_force: np.ndarray  # (ns, n_sensors) each sensor's reading [N] (docs/model.md section 3.15)
    sensor_granule: np.ndarray  # (n_sensors,) int: each sensor's granule
    sensor_load: np.ndarray  # (ng,) scratch: every granule's reading at a sample time [N]
    sensor_n: np.ndarray  # (1,) int: samples recorded


def new_state(ng: int, nm: int, nk: int, nc: int = 6) -> State:
    """A zeroed State for ng granules of nc state columns, nm modes and nk plate contacts."""
    nd = 2 * nk
    z = np.zeros
    return State(
        y=z((ng, nc)),
        acc=z(N_ACC),
        q=z(nm),
        qd=z(nm),
        qdd=z(nm),
        u=z(nd),
        v=z(nd),
        a=z(nd),
        force=z(nd),
        force_prev=z(nd),
        k1=z((ng, nc)),
        k0=z((ng, nc)),
        pforce=z(nd),
        p1=z(5),
        normal=z(nk),
        slip=z(nk),
        clock=z(N_CLOCK),
        count=np.zeros(N_COUNT, np.int64),
        err=z(N_ERR),
    )


def new_work(ng: int, nm: int, nk: int, n_face: int = 0, nc: int = 6, threads: int = 1) -> Work:
    """Shared scratch for ng granules of nc state columns, nm modes, nk plate contacts and
    n_face face nodes, on `threads` threads."""
    nd = 2 * nk
    z = np.zeros
    return Work(
        ytmp=z((ng, nc)),
        ynew=z((ng, nc)),
        k1h=z((ng, nc)),
        k2=z((ng, nc)),
        k3=z((ng, nc)),
        k4=z((ng, nc)),
        kend=z((ng, nc)),
        up=z(nd),
        vp=z(nd),
        fguess=z(nd),
        fbar=z(nk),
        stage=z((4, nd)),
        fnew=z(nd),
        fscratch=z(nd),
        pend=z(5),
        dacc=z(6),
        p1h=z(5),
        normal_new=z(nk),
        slip_new=z(nk),
        nscratch=z(nk),
        sscratch=z(nk),
        conv_iter=np.zeros(nk, np.int64),
        dmode=z((N_LEVELS + 1, nm)),
        gmat=z((N_LEVELS + 1, nd, nd)),
        g_ok=np.zeros(N_LEVELS + 1, np.int64),
        lam_int=z(nk),
        it_int=np.zeros(nk, np.int64),
        dt_int=z(2),
        res_int=z(1),
        yref=z((ng, 3)),
        ovl=z(ng),
        ovl_with=np.zeros(ng, np.int64),
        plate_free=np.zeros(ng, np.int64),
        ovl_new=z(1),
        ovl_who=np.full(2, -1, np.int64),
        wface=z(n_face),
        patch_y=z(nk),
        pweight=z((nk, n_face)),
        prange=np.zeros((nk, 2), np.int64),
        wflag=np.zeros(max(threads, 1), np.int64),
    )


def new_output(
    times: np.ndarray,
    ng: int,
    nm: int,
    nk: int,
    nc: int = 6,
    n_walls: int = 0,
    n_drives: int = 0,
    sensor_times: np.ndarray | None = None,
    sensor_granules: np.ndarray | None = None,
) -> Output:
    """Output buffers for the given output times (nc state columns per granule, n_walls
    walls, n_drives drives) and the sensors' sample times of the sensors in the granules
    `sensor_granules` (None: no sensors)."""
    z = np.zeros
    n_out = len(times)
    gs = np.zeros(0, np.int64) if sensor_granules is None else np.asarray(sensor_granules, np.int64)
    ts = np.zeros(0) if sensor_times is None or len(gs) == 0 else np.asarray(sensor_times, float)
    return Output(
        target=np.asarray(times, float).copy(),
        t=z(n_out),
        y=z((n_out, ng, nc)),
        energy=z((n_out, N_ENERGY)),
        q=z((n_out, nm)),
        qd=z((n_out, nm)),
        force=z((n_out, nk, 2)),
        slip=z((n_out, nk)),
        lam=z((n_out, nk)),
        iters=np.zeros((n_out, nk), np.int64),
        stats=z((n_out, N_STEPSTAT)),
        wall_force=z((n_out, n_walls)),
        drive=z((n_out, n_drives, 2)),
        sensor_target=ts.copy(),
        sensor_t=z(len(ts)),
        sensor_force=z((len(ts), len(gs))),
        sensor_granule=gs.copy(),
        sensor_load=z(ng),
        sensor_n=np.zeros(1, np.int64),
    )

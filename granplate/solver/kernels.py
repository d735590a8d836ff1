"""The compiled time loop: granules by RK4, the plate by Newmark in modal coordinates,
coupled by the paper's interpolation-iteration scheme (MODEL.md section 6).

Everything here is numba-compiled (cached on disk) and takes only arrays and named
tuples of arrays; nothing is allocated per step and no Python runs per step. The Python
side (simulate.py) builds the arrays once, calls `advance` in chunks (for progress), and
turns the output buffers into a Dataset.

One step t_n -> t_n+1 = t_n + h ("paper" scheme):
1. plate predictor (modal Newmark, beta = 1/4, gamma = 1/2): the driving-DOF acceleration
   at t_n+1 is affine in the interface forces F_n+1: a_n+1 = a* + G(h) F_n+1, where
   G(h) = Phi_d diag(1 / (1 + h^2 omega^2 / 4)) Phi_d^T is the driving-DOF block of
   (M + h^2 K / 4)^-1 (the same matrix as in criterion (8));
2. guess F_n+1, move the contact points inside the step with Newmark's constant average
   acceleration (a_n + a_n+1)/2 (the interpolation), advance the granules by RK4 through
   it, recompute F_n+1 from the new granule state; repeat until F_n+1 agrees to
   rtol |F| + atol (the iteration);
3. advance every plate mode with the converged forces; step control keeps the largest
   frictional local-map modulus |lambda| (eq. 8) near `lambda_target`; a step whose
   iteration does not converge is retried at half size.
Time steps live on a geometric ladder h_l = dt_max 2^(-l/4) so that G(h) is computed once
per level and cached (changing the step never refactors the plate).

One step of the "implicit" scheme (the default):
1. the plate modes are advanced exactly for interface forces linear over the step
   (Newmark above omega h = EXACT_OMEGA_H, where the exact response would alias), so the
   driving DOFs' motion at t + h/2 and t + h is affine in the unknowns U (exact_predict,
   exact_matrices); the normal forces are linear from N_n to U, the plate-contact
   friction is held at U over the step for the plate and the granule alike (backward
   Euler for the stiff friction: L-stable, no stick chatter), its work booked exactly;
2. U is found by Newton in (normal force, end slip rate) with the full Jacobian, the
   contacts coupled through the plate (newton_update);
3. the step is accepted, or redone smaller, on a local error estimate (the distance of
   the interface and granule forces from their extrapolation) and the growth of the
   energy residual; steps are output_interval / 2^k and tile every output interval.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from granplate.physics.contact import contact_response, friction_magnitude, local_map_modulus
from granplate.physics.shock import time_profile

# --- layout of the small bookkeeping arrays -------------------------------------------
# clock (float64)
T_NOW, H_LAST, E_IN_MAX, E_ZERO, E_POT, CUSTOM_H, F_SCALE, RES_LAST = 0, 1, 2, 3, 4, 5, 6, 7
N_CLOCK = 10
# count (int64)
C_STEPS, C_LEVEL, C_OUT, C_ITERS, C_RETRIES = 0, 1, 2, 3, 4
N_COUNT = 8
# acc (float64): integrated powers
A_SHOCK_G, A_VISC, A_FRIC, A_SHOCK_P = 0, 1, 2, 3
N_ACC = 4
# energy output columns
(
    E_SHOCK, E_GRAN, E_PLATE, D_VISC, D_FRIC, KE_X, KE_Y, KE_ROT, RESID, RESID_MAX, E_POTG,
) = range(11)
N_ENERGY = 11
# step-statistics output columns
S_STEPS, S_DT_MIN, S_DT_MAX, S_ITERS, S_RETRIES, S_LAM_MAX = range(6)
N_STEPSTAT = 6
# error record (float64)
ERR_T, ERR_CONTACT, ERR_N, ERR_VT, ERR_LAM, ERR_H, ERR_RESID, ERR_ITER = range(8)
N_ERR = 8
# status codes returned by `advance`
OK, ERR_NAN, ERR_ENERGY, ERR_NOCONV, ERR_BUFFER = 0, 1, 2, 3, 4

SCHEME_PAPER, SCHEME_IMPLICIT = 0, 1
LEVEL_RATIO = 2.0 ** -0.25
#: RK4 stays stable for h * rate < 2.785 on a decaying mode; the step control keeps
#: h * (friction relaxation rate of every granule contact) below this bound.
RK4_FRICTION_LIMIT = 1.0
N_LEVELS = 200
#: implicit scheme: a step whose error estimate exceeds REJECT_FACTOR * error_tol is redone smaller.
REJECT_FACTOR = 2.0
#: implicit scheme: the step is at most the shock's duration / SHOCK_STEPS while it acts.
SHOCK_STEPS = 100
#: implicit scheme: share of solver.energy_tol the step control lets the residual drift over a run.
ENERGY_STEP_FRACTION = 0.5


class Granular(NamedTuple):
    """Flat arrays of the granular medium and its contacts (SI units).

    mass, inertia, radius: (ng,); pair_ij: (np, 2) granule indices; pair_coef: (np, 4)
    [A, c, mu, k_s] with gamma = c delta^(1/4); wall_i: (nw,); wall_geo: (nw, 3)
    [nx, ny, offset]; wall_coef: (nw, 4); pc_i: (nk,) granule of each plate contact;
    pc_x: (nk,) undeformed x of the plate edge; pc_coef: (nk, 4); shock_force,
    shock_torque: (ng,) load resultants per unit q0 [m, m^2].
    """

    mass: np.ndarray
    inertia: np.ndarray
    radius: np.ndarray
    pair_ij: np.ndarray
    pair_coef: np.ndarray
    wall_i: np.ndarray
    wall_geo: np.ndarray
    wall_coef: np.ndarray
    pc_i: np.ndarray
    pc_x: np.ndarray
    pc_coef: np.ndarray
    shock_force: np.ndarray
    shock_torque: np.ndarray


class PlateArrays(NamedTuple):
    """The plate in mass-normalised modal coordinates.

    omega2: (nm,) squared circular frequencies [rad^2/s^2]; phi_d: (nd, nm) mode shapes
    at the driving DOFs (x, y of each contact); load_modal: (nm,) modal edge load per
    unit q0 (zeros when the shock is on the granules).
    """

    omega2: np.ndarray
    phi_d: np.ndarray
    load_modal: np.ndarray


class Config(NamedTuple):
    """Scalar settings of the loop."""

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
    arm_shrink: float = 0.0  # 0: friction arm R (MODEL.md); 1: arm to the contact point
    scheme: int = 0  # SCHEME_PAPER or SCHEME_IMPLICIT
    error_tol: float = 1e-3  # implicit scheme: local error target of the step control
    force_floor: float = 0.0  # implicit scheme: smallest force scale of the error estimate [N]


class State(NamedTuple):
    """Everything at t_n (updated in place by `advance`)."""

    y: np.ndarray  # (ng, 6): x, y, theta, vx, vy, omega
    acc: np.ndarray  # (N_ACC,)
    q: np.ndarray  # (nm,)
    qd: np.ndarray
    qdd: np.ndarray
    u: np.ndarray  # (nd,) driving-DOF displacement, velocity, acceleration
    v: np.ndarray
    a: np.ndarray
    force: np.ndarray  # (nd,) interface force on the plate
    force_prev: np.ndarray
    k1: np.ndarray  # (ng, 6) time derivative at t_n
    k0: np.ndarray  # (ng, 6) time derivative at t_n-1
    pforce: np.ndarray  # (nd,) the plate's end-force history P_n (Newmark bookkeeping)
    p1: np.ndarray  # (3,) shock, viscous, friction power at t_n
    normal: np.ndarray  # (nk,) |N| at plate contacts
    slip: np.ndarray  # (nk,) tangential slip rate at plate contacts
    clock: np.ndarray
    count: np.ndarray
    err: np.ndarray


class Work(NamedTuple):
    """Scratch arrays (allocated once)."""

    ytmp: np.ndarray
    ynew: np.ndarray
    k2: np.ndarray
    k3: np.ndarray
    k4: np.ndarray
    kend: np.ndarray
    up: np.ndarray
    vp: np.ndarray
    astar: np.ndarray
    anext: np.ndarray
    aavg: np.ndarray
    fguess: np.ndarray
    stage: np.ndarray  # (4, nd) driving-DOF u, v at t + h/2 and u, v at t + h
    ustar: np.ndarray  # (4, nd) implicit scheme: their known part
    jac: np.ndarray  # (nd, nd) implicit scheme: Newton matrix
    rhs: np.ndarray  # (nd,)
    vguess: np.ndarray  # (nk,) implicit scheme: Newton iterate of the end slip rates
    mcoef: np.ndarray  # (N_LEVELS + 1, nm, N_MCOEF) implicit scheme: exact modal coefficients
    mmat: np.ndarray  # (N_LEVELS + 1, 4, nd, nd) implicit scheme: response to the unknowns
    qn: np.ndarray  # (nm,) implicit scheme: modal state at the end of the step being tried
    qdn: np.ndarray
    fbar: np.ndarray  # (nk,) implicit scheme: plate-contact friction held over the step
    k1i: np.ndarray  # (ng, 6) implicit scheme: stage-1 derivative with fbar
    p1i: np.ndarray  # (3,)
    fnew: np.ndarray
    fscratch: np.ndarray
    pend: np.ndarray
    dacc: np.ndarray
    qdd_star: np.ndarray
    normal_new: np.ndarray
    slip_new: np.ndarray
    nscratch: np.ndarray
    sscratch: np.ndarray
    conv_iter: np.ndarray  # (nk,) int
    dmode: np.ndarray  # (N_LEVELS + 1, nm)
    gmat: np.ndarray  # (N_LEVELS + 1, nd, nd)
    g_ok: np.ndarray  # (N_LEVELS + 1,) int
    lam_int: np.ndarray  # (nk,) max |lambda| since last output
    it_int: np.ndarray  # (nk,) max iterations since last output
    dt_int: np.ndarray  # (2,) min, max step since last output
    res_int: np.ndarray  # (1,) max |residual| since last output


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


# --- forces -------------------------------------------------------------------------------


@njit(cache=True)
def granular_rhs(t, y, up, vp, g, cfg, dy, fplate, normal, slip, hold, fbar):
    """Time derivative of the granular state and the plate-contact forces.

    y: (ng, 6) state; up, vp: driving-DOF displacement and velocity at t; writes dy,
    fplate (nd,) = force ON the plate [N, N], normal and slip at each plate contact.
    hold: the plate-contact friction is fbar[k] (held over the step, implicit scheme)
    instead of mu |N| tanh(k_s v_t).
    Returns (shock power, viscous power, friction power, contact potential energy,
    largest friction relaxation rate of a granule contact) [W, J, 1/s]. That rate,
    mu k_s |N| cosh^-2(k_s v_t) (1/m_i + 1/m_j + a_i^2/I_i + a_j^2/I_j), is how fast the
    slip of a sticking contact relaxes; RK4 needs h times it below ~2.8.
    """
    ng = y.shape[0]
    for i in range(ng):
        dy[i, 0] = y[i, 3]
        dy[i, 1] = y[i, 4]
        dy[i, 2] = y[i, 5]
        dy[i, 3] = 0.0
        dy[i, 4] = 0.0
        dy[i, 5] = 0.0
    p_shock = 0.0
    p_visc = 0.0
    p_fric = 0.0
    e_pot = 0.0
    rate = 0.0
    # shock on the loaded granules
    if not cfg.load_on_plate:
        amp = cfg.q0 * time_profile(t, cfg.duration)
        if amp != 0.0:
            for i in range(ng):
                fx = amp * g.shock_force[i]
                tq = amp * g.shock_torque[i]
                dy[i, 3] += fx
                dy[i, 5] += tq
                p_shock += fx * y[i, 3] + tq * y[i, 5]
    # granule-granule contacts
    for p in range(g.pair_ij.shape[0]):
        i = g.pair_ij[p, 0]
        j = g.pair_ij[p, 1]
        ri = g.radius[i]
        rj = g.radius[j]
        dx = y[j, 0] - y[i, 0]
        dz = y[j, 1] - y[i, 1]
        dist = math.sqrt(dx * dx + dz * dz)
        delta = ri + rj - dist
        if delta <= 0.0:
            continue
        nx = dx / dist
        nz = dz / dist
        ddot = -((y[j, 3] - y[i, 3]) * nx + (y[j, 4] - y[i, 4]) * nz)
        ai = ri - 0.5 * cfg.arm_shrink * delta
        aj = rj - 0.5 * cfg.arm_shrink * delta
        vt = -(y[i, 3] - y[j, 3]) * nz + (y[i, 4] - y[j, 4]) * nx + ai * y[i, 5] + aj * y[j, 5]
        c = g.pair_coef[p]
        n, f, pv, pf, ep = contact_response(delta, ddot, vt, c[0], c[1], c[2], c[3], cfg.clip)
        rate = max(rate, slip_relaxation_rate(n, vt, c[2], c[3], 1.0 / g.mass[i] + 1.0 / g.mass[j]
                                              + ai * ai / g.inertia[i] + aj * aj / g.inertia[j]))
        # on i: -n nvec - f tvec, tvec = (-nz, nx); on j the opposite
        fx = -n * nx + f * nz
        fz = -n * nz - f * nx
        dy[i, 3] += fx
        dy[i, 4] += fz
        dy[j, 3] -= fx
        dy[j, 4] -= fz
        dy[i, 5] -= f * ai
        dy[j, 5] -= f * aj
        p_visc += pv
        p_fric += pf
        e_pot += ep
    # rigid walls
    for w in range(g.wall_i.shape[0]):
        i = g.wall_i[w]
        ri = g.radius[i]
        nx = g.wall_geo[w, 0]
        nz = g.wall_geo[w, 1]
        delta = y[i, 0] * nx + y[i, 1] * nz + ri - g.wall_geo[w, 2]
        if delta <= 0.0:
            continue
        ddot = y[i, 3] * nx + y[i, 4] * nz
        ai = ri - cfg.arm_shrink * delta
        vt = -y[i, 3] * nz + y[i, 4] * nx + ai * y[i, 5]
        c = g.wall_coef[w]
        n, f, pv, pf, ep = contact_response(delta, ddot, vt, c[0], c[1], c[2], c[3], cfg.clip)
        rate = max(rate, slip_relaxation_rate(n, vt, c[2], c[3], 1.0 / g.mass[i] + ai * ai / g.inertia[i]))
        dy[i, 3] += -n * nx + f * nz
        dy[i, 4] += -n * nz - f * nx
        dy[i, 5] -= f * ai
        p_visc += pv
        p_fric += pf
        e_pot += ep
    # plate contacts through the rigid layers (n = (1, 0), t = (0, 1))
    for k in range(g.pc_i.shape[0]):
        i = g.pc_i[k]
        ri = g.radius[i]
        delta = y[i, 0] + ri - (g.pc_x[k] + up[2 * k])
        ddot = y[i, 3] - vp[2 * k]
        ai = ri - cfg.arm_shrink * max(delta, 0.0)
        vt = y[i, 4] - vp[2 * k + 1] + ai * y[i, 5]
        n = 0.0
        f = 0.0
        pf = 0.0
        if delta > 0.0:
            c = g.pc_coef[k]
            n, f, pv, pf, ep = contact_response(delta, ddot, vt, c[0], c[1], c[2], c[3], cfg.clip)
            if not hold:
                # the granule side only: the plate side of this map is criterion (8)
                rate = max(rate, slip_relaxation_rate(n, vt, c[2], c[3], 1.0 / g.mass[i] + ai * ai / g.inertia[i]))
            dy[i, 3] -= n
            p_visc += pv
            e_pot += ep
        if hold:
            f = fbar[k]
            pf = 0.0  # its work is added exactly after the step (held_friction_work)
        if f != 0.0:
            dy[i, 4] -= f
            dy[i, 5] -= f * ai
            p_fric += pf
        fplate[2 * k] = n
        fplate[2 * k + 1] = f
        normal[k] = n
        slip[k] = vt
    for i in range(ng):
        dy[i, 3] /= g.mass[i]
        dy[i, 4] /= g.mass[i]
        dy[i, 5] /= g.inertia[i]
    return p_shock, p_visc, p_fric, e_pot, rate


@njit(cache=True)
def slip_relaxation_rate(n, vt, mu, k_s, inv_mass_t):
    """d(friction)/d(slip) times the contact's tangential inverse mass [1/s]."""
    if n <= 0.0:
        return 0.0
    ch = math.cosh(k_s * vt)
    return mu * k_s * n / (ch * ch) * inv_mass_t


@njit(cache=True)
def stage_motion_newmark(h, st, w):
    """Driving-DOF motion at t + h/2 and t + h inside a Newmark step ("paper" scheme).

    Constant average acceleration aavg = (a_n + a_n+1)/2: u(s) = u_n + v_n s + aavg s^2/2,
    v(s) = v_n + aavg s; at s = h this is exactly Newmark's update (the interpolation of
    the paper's scheme). Writes w.stage rows u(h/2), v(h/2), u(h), v(h).
    """
    hh = 0.5 * h
    for d in range(st.u.shape[0]):
        aavg = w.aavg[d]
        w.stage[0, d] = st.u[d] + st.v[d] * hh + 0.5 * aavg * hh * hh
        w.stage[1, d] = st.v[d] + aavg * hh
        w.stage[2, d] = st.u[d] + st.v[d] * h + 0.5 * aavg * h * h
        w.stage[3, d] = st.v[d] + aavg * h


@njit(cache=True)
def stage_motion_exact(mmat, w):
    """Driving-DOF motion at t + h/2 and t + h of the exactly integrated plate
    ("implicit" scheme): the free/known part w.ustar plus the response mmat to the
    unknown interface forces w.fguess. Writes w.stage (rows as in stage_motion_newmark).
    """
    nd = w.fguess.shape[0]
    for r in range(4):
        for d in range(nd):
            acc = w.ustar[r, d]
            for e in range(nd):
                acc += mmat[r, d, e] * w.fguess[e]
            w.stage[r, d] = acc


@njit(cache=True)
def rk4_granular_step(t, h, st, g, cfg, w):
    """One RK4 step of the granules with the contact points moving as w.stage says
    (rows: u, v at t + h/2, then u, v at t + h; see `stage_motion_newmark` and
    `stage_motion_exact`).

    Reuses st.k1/st.p1 (FSAL); writes w.ynew, w.kend, w.fnew (forces on the plate at
    t + h), w.pend, w.dacc (integrated shock, viscous, friction work over the step).
    """
    y0 = st.y
    ng = y0.shape[0]
    hold = cfg.scheme == SCHEME_IMPLICIT
    k1 = st.k1
    p1 = st.p1
    if hold:  # stage 1 depends on the held friction: no FSAL
        for d in range(st.u.shape[0]):
            w.up[d] = st.u[d]
            w.vp[d] = st.v[d]
        pr = granular_rhs(t, y0, w.up, w.vp, g, cfg, w.k1i, w.fscratch, w.nscratch, w.sscratch, True, w.fbar)
        w.p1i[0] = pr[0]
        w.p1i[1] = pr[1]
        w.p1i[2] = pr[2]
        k1 = w.k1i
        p1 = w.p1i
    hh = 0.5 * h
    for d in range(st.u.shape[0]):
        w.up[d] = w.stage[0, d]
        w.vp[d] = w.stage[1, d]
    for i in range(ng):
        for c in range(6):
            w.ytmp[i, c] = y0[i, c] + hh * k1[i, c]
    p2 = granular_rhs(t + hh, w.ytmp, w.up, w.vp, g, cfg, w.k2, w.fscratch, w.nscratch, w.sscratch, hold, w.fbar)
    for i in range(ng):
        for c in range(6):
            w.ytmp[i, c] = y0[i, c] + hh * w.k2[i, c]
    p3 = granular_rhs(t + hh, w.ytmp, w.up, w.vp, g, cfg, w.k3, w.fscratch, w.nscratch, w.sscratch, hold, w.fbar)
    for d in range(st.u.shape[0]):
        w.up[d] = w.stage[2, d]
        w.vp[d] = w.stage[3, d]
    for i in range(ng):
        for c in range(6):
            w.ytmp[i, c] = y0[i, c] + h * w.k3[i, c]
    p4 = granular_rhs(t + h, w.ytmp, w.up, w.vp, g, cfg, w.k4, w.fscratch, w.nscratch, w.sscratch, hold, w.fbar)
    h6 = h / 6.0
    for i in range(ng):
        for c in range(6):
            w.ynew[i, c] = y0[i, c] + h6 * (k1[i, c] + 2.0 * w.k2[i, c] + 2.0 * w.k3[i, c] + w.k4[i, c])
    w.dacc[0] = h6 * (p1[0] + 2.0 * p2[0] + 2.0 * p3[0] + p4[0])
    w.dacc[1] = h6 * (p1[1] + 2.0 * p2[1] + 2.0 * p3[1] + p4[1])
    w.dacc[2] = h6 * (p1[2] + 2.0 * p2[2] + 2.0 * p3[2] + p4[2])
    pe = granular_rhs(t + h, w.ynew, w.up, w.vp, g, cfg, w.kend, w.fnew, w.normal_new, w.slip_new, False, w.fbar)
    if hold:
        held_friction_target(st, g, w)
    w.pend[0] = pe[0]
    w.pend[1] = pe[1]
    w.pend[2] = pe[2]
    return pe[3], pe[4]


@njit(cache=True)
def held_friction_target(st, g, w):
    """The value the held plate-contact friction must take (implicit scheme).

    fbar = mu Nbar tanh(k_s v_t,n+1) with Nbar = (|N_n| + |N_n+1|)/2: the slip rate at
    the end of the step (backward Euler, which damps the stiff stick regime without
    chatter) but the normal force averaged over the step, so that in gross slip, where
    tanh is saturated, the friction impulse is second-order accurate like the normal one.
    """
    for k in range(g.pc_i.shape[0]):
        nbar = 0.5 * (st.normal[k] + w.normal_new[k])
        w.fnew[2 * k + 1] = friction_magnitude(nbar, w.slip_new[k], g.pc_coef[k, 2], g.pc_coef[k, 3])


# --- plate --------------------------------------------------------------------------------


@njit(cache=True)
def step_matrices(h, p, dmode, gmat):
    """For step h: dmode[m] = 1/(1 + h^2 omega_m^2/4) and G(h) = Phi_d diag(dmode) Phi_d^T."""
    nm = p.omega2.shape[0]
    nd = p.phi_d.shape[0]
    for m in range(nm):
        dmode[m] = 1.0 / (1.0 + 0.25 * h * h * p.omega2[m])
    for a in range(nd):
        for b in range(a, nd):
            s = 0.0
            for m in range(nm):
                s += p.phi_d[a, m] * dmode[m] * p.phi_d[b, m]
            gmat[a, b] = s
            gmat[b, a] = s


@njit(cache=True)
def newmark_predict(t, h, st, p, cfg, dmode, qdd_star, astar):
    """Plate predictor: q''* = (f_ext(t+h) - omega^2 (q + h q' + h^2/4 q'')) dmode and
    a* = Phi_d q''*, so that a_n+1 = a* + G(h) F_n+1 at the driving DOFs."""
    nm = p.omega2.shape[0]
    nd = p.phi_d.shape[0]
    amp = 0.0
    if cfg.load_on_plate:
        amp = cfg.q0 * time_profile(t + h, cfg.duration)
    for m in range(nm):
        qt = st.q[m] + h * st.qd[m] + 0.25 * h * h * st.qdd[m]
        qdd_star[m] = (amp * p.load_modal[m] - p.omega2[m] * qt) * dmode[m]
    for d in range(nd):
        s = 0.0
        for m in range(nm):
            s += p.phi_d[d, m] * qdd_star[m]
        astar[d] = s


@njit(cache=True)
def newmark_correct(t, h, st, p, cfg, dmode, qdd_star, force):
    """Advance every mode with the converged interface forces (Newmark average
    acceleration); returns the work of the edge load over the step (trapezoidal, which
    is exact for this scheme's energy balance) [J]."""
    nm = p.omega2.shape[0]
    nd = p.phi_d.shape[0]
    amp0 = 0.0
    amp1 = 0.0
    if cfg.load_on_plate:
        amp0 = cfg.q0 * time_profile(t, cfg.duration)
        amp1 = cfg.q0 * time_profile(t + h, cfg.duration)
    work = 0.0
    for m in range(nm):
        proj = 0.0
        for d in range(nd):
            proj += p.phi_d[d, m] * force[d]
        qdd1 = qdd_star[m] + dmode[m] * proj
        qt = st.q[m] + h * st.qd[m] + 0.25 * h * h * st.qdd[m]
        q1 = qt + 0.25 * h * h * qdd1
        work += 0.5 * (amp0 + amp1) * p.load_modal[m] * (q1 - st.q[m])
        st.qd[m] += 0.5 * h * (st.qdd[m] + qdd1)
        st.q[m] = q1
        st.qdd[m] = qdd1
    return work


# --- modal integration of the "implicit" scheme ---------------------------------------------
# Each mode is a harmonic oscillator q'' + omega^2 q = f(s) whose force is linear over the
# step, f(s) = f0 + (f1 - f0) s / h (a held friction force has f0 = f1). Every mode's
# state at s = h/2 and s = h is linear in (q0, qd0, f0, f1); mcoef holds, per ladder level
# and mode, the coefficients, for s = h/2 (base 0) and s = h (base MC_STRIDE):
#   q(s) = QQ q0 + QV qd0 + QF0 f0 + QF1 f1,   qd(s) = VQ q0 + VV qd0 + VF0 f0 + VF1 f1,
# and of the integral of q over the step (for the work of the plate's edge load):
#   int q = IQ q0 + IV qd0 + IF0 f0 + IF1 f1.
# Modes with omega h <= EXACT_OMEGA_H are integrated exactly (no period error however
# large the step); the stiffer ones by Newmark's average acceleration, which keeps them
# quasi-static and bounded (their exact response, sampled once per step, would alias).
MC_QQ, MC_QV, MC_QF0, MC_QF1, MC_VQ, MC_VV, MC_VF0, MC_VF1 = range(8)
MC_STRIDE = 8
MC_IQ, MC_IV, MC_IF0, MC_IF1 = 16, 17, 18, 19
N_MCOEF = 20
#: modes with omega h up to this are integrated exactly, stiffer ones by Newmark.
EXACT_OMEGA_H = 1.0


@njit(cache=True)
def sinc(x):
    """sin(x)/x."""
    if abs(x) < 1e-4:
        return 1.0 - x * x / 6.0
    return math.sin(x) / x


@njit(cache=True)
def one_minus_cos_over_x2(x):
    """(1 - cos x)/x^2, without cancellation."""
    sh = sinc(0.5 * x)
    return 0.5 * sh * sh


@njit(cache=True)
def x_minus_sin_over_x3(x):
    """(x - sin x)/x^3, by its series for small x."""
    if abs(x) < 0.1:
        x2 = x * x
        return 1.0 / 6.0 - x2 * (1.0 / 120.0 - x2 * (1.0 / 5040.0 - x2 / 362880.0))
    return (x - math.sin(x)) / (x * x * x)


@njit(cache=True)
def cos_remainder_over_x4(x):
    """(x^2/2 - 1 + cos x)/x^4, by its series for small x."""
    if abs(x) < 0.2:
        x2 = x * x
        return 1.0 / 24.0 - x2 * (1.0 / 720.0 - x2 * (1.0 / 40320.0 - x2 / 3628800.0))
    return (0.5 * x * x - 1.0 + math.cos(x)) / (x * x * x * x)


@njit(cache=True)
def exact_mode_coefficients(h, w2, row):
    """Exact response of q'' + w2 q = f0 + (f1 - f0) s/h (layout: MC_*)."""
    om = math.sqrt(max(w2, 0.0))
    for j in range(2):
        s = 0.5 * h if j == 0 else h
        x = om * s
        sw = s * sinc(x)  # sin(omega s)/omega
        a = s * s * one_minus_cos_over_x2(x)  # (1 - cos)/omega^2
        b = s * s * s * x_minus_sin_over_x3(x) / h  # (s - sw)/(omega^2 h)
        c = math.cos(x)
        base = j * MC_STRIDE
        row[base + MC_QQ] = c
        row[base + MC_QV] = sw
        row[base + MC_QF0] = a - b
        row[base + MC_QF1] = b
        row[base + MC_VQ] = -w2 * sw
        row[base + MC_VV] = c
        row[base + MC_VF0] = sw - a / h
        row[base + MC_VF1] = a / h
    x = om * h
    qa = h * h * h * x_minus_sin_over_x3(x)
    qb = h * h * h * cos_remainder_over_x4(x)
    row[MC_IQ] = row[MC_STRIDE + MC_QV]
    row[MC_IV] = row[MC_STRIDE + MC_QF0] + row[MC_STRIDE + MC_QF1]
    row[MC_IF0] = qa - qb
    row[MC_IF1] = qb


@njit(cache=True)
def newmark_mode_coefficients(h, w2, row):
    """Newmark (beta 1/4, gamma 1/2) for the same oscillator, with the acceleration at
    the start consistent with f0 and the motion inside the step at the constant average
    acceleration (the interpolation of the paper's scheme); the integral of q is the
    trapezoid h (q0 + q1)/2, which makes the edge-load work (L0 + L1)/2 (q1 - q0), the
    work Newmark's energy identity balances (layout: MC_*)."""
    dd = 1.0 / (1.0 + 0.25 * h * h * w2)
    # a1 = qdd at the end; aavg = (qdd0 + qdd1)/2, qdd0 = f0 - w2 q0
    a1_q = -w2 * dd * (1.0 - 0.25 * h * h * w2)
    a1_v = -w2 * dd * h
    a1_f0 = -0.25 * w2 * dd * h * h
    a1_f1 = dd
    m_q = 0.5 * (-w2 + a1_q)
    m_v = 0.5 * a1_v
    m_f0 = 0.5 * (1.0 + a1_f0)
    m_f1 = 0.5 * a1_f1
    for j in range(2):
        s = 0.5 * h if j == 0 else h
        base = j * MC_STRIDE
        hs = 0.5 * s * s
        row[base + MC_QQ] = 1.0 + hs * m_q
        row[base + MC_QV] = s + hs * m_v
        row[base + MC_QF0] = hs * m_f0
        row[base + MC_QF1] = hs * m_f1
        row[base + MC_VQ] = s * m_q
        row[base + MC_VV] = 1.0 + s * m_v
        row[base + MC_VF0] = s * m_f0
        row[base + MC_VF1] = s * m_f1
    hb = 0.5 * h
    row[MC_IQ] = hb * (1.0 + row[MC_STRIDE + MC_QQ])
    row[MC_IV] = hb * row[MC_STRIDE + MC_QV]
    row[MC_IF0] = hb * row[MC_STRIDE + MC_QF0]
    row[MC_IF1] = hb * row[MC_STRIDE + MC_QF1]


@njit(cache=True)
def modal_coefficients(h, omega2, coef):
    """Fill coef (nm, N_MCOEF) for a step h: exact for omega h <= EXACT_OMEGA_H, else
    Newmark."""
    for m in range(omega2.shape[0]):
        if omega2[m] * h * h <= EXACT_OMEGA_H * EXACT_OMEGA_H:
            exact_mode_coefficients(h, omega2[m], coef[m])
        else:
            newmark_mode_coefficients(h, omega2[m], coef[m])


@njit(cache=True)
def exact_matrices(phi_d, coef, mmat):
    """Response of the driving DOFs to the unknown interface forces U over one step.

    mmat[r] (r = u(h/2), v(h/2), u(h), v(h)) = Phi_d diag(c_r) Phi_d^T column by column:
    a normal force (even DOF) is linear over the step and U is its end value (c_r = the
    f1 coefficient); a friction force (odd DOF) is held over the step at U (c_r = the f0
    plus the f1 coefficient).
    """
    nd = phi_d.shape[0]
    nm = phi_d.shape[1]
    for r in range(4):
        base = (r // 2) * MC_STRIDE
        c0 = base + (MC_QF0 if r % 2 == 0 else MC_VF0)
        c1 = base + (MC_QF1 if r % 2 == 0 else MC_VF1)
        for d in range(nd):
            for e in range(nd):
                held = e % 2 == 1
                acc = 0.0
                for m in range(nm):
                    c = coef[m, c1] + (coef[m, c0] if held else 0.0)
                    acc += phi_d[d, m] * c * phi_d[e, m]
                mmat[r, d, e] = acc


@njit(cache=True)
def exact_predict(t, h, st, p, cfg, coef, w):
    """Known part of the driving-DOF motion at t + h/2 and t + h (w.ustar): the free
    vibration, the edge load (linear over the step) and the normal forces' start values
    N_n (st.pforce, even DOFs); the unknowns' share is added by stage_motion_exact."""
    nm = p.omega2.shape[0]
    nd = p.phi_d.shape[0]
    amp0 = 0.0
    amp1 = 0.0
    if cfg.load_on_plate:
        amp0 = cfg.q0 * time_profile(t, cfg.duration)
        amp1 = cfg.q0 * time_profile(t + h, cfg.duration)
    for r in range(4):
        for d in range(nd):
            w.ustar[r, d] = 0.0
    for m in range(nm):
        f0 = amp0 * p.load_modal[m]
        for d in range(0, nd, 2):
            f0 += p.phi_d[d, m] * st.pforce[d]
        f1 = amp1 * p.load_modal[m]
        q0 = st.q[m]
        v0 = st.qd[m]
        for r in range(4):
            base = (r // 2) * MC_STRIDE + (0 if r % 2 == 0 else MC_VQ)
            val = coef[m, base] * q0 + coef[m, base + 1] * v0 + coef[m, base + 2] * f0 + coef[m, base + 3] * f1
            for d in range(nd):
                w.ustar[r, d] += p.phi_d[d, m] * val


@njit(cache=True)
def exact_correct(t, h, st, p, cfg, coef, force, qn, qdn):
    """Every mode at the end of the step (into qn, qdn) with the interface forces `force`
    (normal: linear from st.pforce to force; friction: held at force). Returns the work
    of the edge load over the step (exact for its linear interpolation) [J] and the plate
    energy at the end [J]."""
    nm = p.omega2.shape[0]
    nd = p.phi_d.shape[0]
    amp0 = 0.0
    amp1 = 0.0
    if cfg.load_on_plate:
        amp0 = cfg.q0 * time_profile(t, cfg.duration)
        amp1 = cfg.q0 * time_profile(t + h, cfg.duration)
    work = 0.0
    energy = 0.0
    b = MC_STRIDE
    for m in range(nm):
        f0 = amp0 * p.load_modal[m]
        f1 = amp1 * p.load_modal[m]
        for d in range(nd):
            phi = p.phi_d[d, m]
            f1 += phi * force[d]
            f0 += phi * (force[d] if d % 2 == 1 else st.pforce[d])
        q0 = st.q[m]
        v0 = st.qd[m]
        q1 = coef[m, b + MC_QQ] * q0 + coef[m, b + MC_QV] * v0 + coef[m, b + MC_QF0] * f0 + coef[m, b + MC_QF1] * f1
        v1 = coef[m, b + MC_VQ] * q0 + coef[m, b + MC_VV] * v0 + coef[m, b + MC_VF0] * f0 + coef[m, b + MC_VF1] * f1
        if cfg.load_on_plate:
            qint = coef[m, MC_IQ] * q0 + coef[m, MC_IV] * v0 + coef[m, MC_IF0] * f0 + coef[m, MC_IF1] * f1
            work += p.load_modal[m] * (amp1 * q1 - amp0 * q0 - (amp1 - amp0) * qint / h)
        qn[m] = q1
        qdn[m] = v1
        energy += 0.5 * (v1 * v1 + p.omega2[m] * q1 * q1)
    return work, energy


@njit(cache=True)
def plate_energy(st, p):
    """E_p = 1/2 q'.q' + 1/2 sum omega^2 q^2 = 1/2 v^T M v + 1/2 x^T K x [J] (eq. 9)."""
    e = 0.0
    for m in range(p.omega2.shape[0]):
        e += 0.5 * (st.qd[m] * st.qd[m] + p.omega2[m] * st.q[m] * st.q[m])
    return e


@njit(cache=True)
def kinetic_energies(y, g):
    """Horizontal, vertical and rotational kinetic energy of the granules [J]."""
    kx = 0.0
    ky = 0.0
    kr = 0.0
    for i in range(y.shape[0]):
        kx += 0.5 * g.mass[i] * y[i, 3] * y[i, 3]
        ky += 0.5 * g.mass[i] * y[i, 4] * y[i, 4]
        kr += 0.5 * g.inertia[i] * y[i, 5] * y[i, 5]
    return kx, ky, kr


# --- bookkeeping ---------------------------------------------------------------------------


@njit(cache=True)
def initialise(st, g, p, cfg, w):
    """Forces, accelerations and energies at t = 0 (state y, q, qd already set)."""
    nm = p.omega2.shape[0]
    nd = p.phi_d.shape[0]
    for d in range(nd):
        w.up[d] = st.u[d]
        w.vp[d] = st.v[d]
    pr = granular_rhs(st.clock[T_NOW], st.y, w.up, w.vp, g, cfg, st.k1, st.force, st.normal, st.slip, False, w.fbar)
    st.p1[0] = pr[0]
    st.p1[1] = pr[1]
    st.p1[2] = pr[2]
    st.clock[E_POT] = pr[3]
    amp = 0.0
    if cfg.load_on_plate:
        amp = cfg.q0 * time_profile(st.clock[T_NOW], cfg.duration)
    for m in range(nm):
        proj = 0.0
        for d in range(nd):
            proj += p.phi_d[d, m] * st.force[d]
        st.qdd[m] = amp * p.load_modal[m] + proj - p.omega2[m] * st.q[m]
    for d in range(nd):
        su = 0.0
        sv = 0.0
        sa = 0.0
        for m in range(nm):
            su += p.phi_d[d, m] * st.q[m]
            sv += p.phi_d[d, m] * st.qd[m]
            sa += p.phi_d[d, m] * st.qdd[m]
        st.u[d] = su
        st.v[d] = sv
        st.a[d] = sa
        st.force_prev[d] = st.force[d]
        st.pforce[d] = st.force[d]
    kx, ky, kr = kinetic_energies(st.y, g)
    e0 = kx + ky + kr + pr[3] + plate_energy(st, p)
    st.clock[E_ZERO] = e0
    st.clock[E_IN_MAX] = e0
    reset_interval(w)


@njit(cache=True)
def reset_interval(w):
    """Restart the per-output-interval maxima."""
    for k in range(w.lam_int.shape[0]):
        w.lam_int[k] = 0.0
        w.it_int[k] = 0
    w.dt_int[0] = 1e300
    w.dt_int[1] = 0.0
    w.res_int[0] = 0.0


@njit(cache=True)
def energy_balance(st, g, p):
    """(E_shock, E_g, E_p, residual/E_in_max-free) at t_n: returns the raw terms."""
    kx, ky, kr = kinetic_energies(st.y, g)
    eg = kx + ky + kr + st.clock[E_POT]
    ep = plate_energy(st, p)
    eshock = st.acc[A_SHOCK_G] + st.acc[A_SHOCK_P]
    return eshock, eg, ep, kx, ky, kr


@njit(cache=True)
def record(o, st, g, p, w, out):
    """Write the state at t_n into output row o."""
    eshock, eg, ep, kx, ky, kr = energy_balance(st, g, p)
    e_in = st.clock[E_ZERO] + eshock
    denom = max(st.clock[E_IN_MAX], 1e-300)
    out.t[o] = st.clock[T_NOW]
    for i in range(st.y.shape[0]):
        for c in range(6):
            out.y[o, i, c] = st.y[i, c]
    out.energy[o, E_SHOCK] = eshock
    out.energy[o, E_GRAN] = eg
    out.energy[o, E_PLATE] = ep
    out.energy[o, D_VISC] = st.acc[A_VISC]
    out.energy[o, D_FRIC] = st.acc[A_FRIC]
    out.energy[o, KE_X] = kx
    out.energy[o, KE_Y] = ky
    out.energy[o, KE_ROT] = kr
    out.energy[o, RESID] = (eg + ep + st.acc[A_VISC] + st.acc[A_FRIC] - e_in) / denom
    out.energy[o, RESID_MAX] = w.res_int[0]
    out.energy[o, E_POTG] = st.clock[E_POT]
    for m in range(st.q.shape[0]):
        out.q[o, m] = st.q[m]
        out.qd[o, m] = st.qd[m]
    lam_max = 0.0
    for k in range(st.normal.shape[0]):
        out.force[o, k, 0] = st.force[2 * k]
        out.force[o, k, 1] = st.force[2 * k + 1]
        out.slip[o, k] = st.slip[k]
        out.lam[o, k] = w.lam_int[k]
        out.iters[o, k] = w.it_int[k]
        lam_max = max(lam_max, w.lam_int[k])
    out.stats[o, S_STEPS] = st.count[C_STEPS]
    out.stats[o, S_DT_MIN] = w.dt_int[0] if w.dt_int[1] > 0.0 else 0.0
    out.stats[o, S_DT_MAX] = w.dt_int[1]
    out.stats[o, S_ITERS] = st.count[C_ITERS]
    out.stats[o, S_RETRIES] = st.count[C_RETRIES]
    out.stats[o, S_LAM_MAX] = lam_max
    reset_interval(w)


@njit(cache=True)
def level_step(level, cfg):
    """Step of ladder level l: dt_max 2^(-l/4) [s]."""
    return cfg.dt_max * LEVEL_RATIO**level


@njit(cache=True)
def dyadic_level(level, pos, cfg):
    """Implicit scheme: the ladder level to use at `pos` [s] into the output interval.

    Only every fourth level, h = dt_max / 2^k, with dt_max = out_dt / 2^j (model.py), and
    a step starts only where it fits a whole number of times since the last output, so
    the steps tile every output interval and land on it without a step of odd size (whose
    modal coefficients would have to be recomputed)."""
    lv = level + (-level) % 4
    while lv + 4 < N_LEVELS:
        r = pos / level_step(lv, cfg)
        if abs(r - round(r)) <= 1e-6:
            break
        lv += 4
    return lv


@njit(cache=True)
def level_for(h, cfg):
    """Smallest ladder level whose step does not exceed h."""
    if h >= cfg.dt_max:
        return 0
    lv = int(math.ceil(math.log(h / cfg.dt_max) / math.log(LEVEL_RATIO) - 1e-9))
    return min(max(lv, 0), N_LEVELS - 1)


# --- the loop -----------------------------------------------------------------------------


@njit(cache=True)
def level_matrices(h, implicit, p, w, slot):
    """Everything a step of size h needs, computed once per ladder level: Newmark's
    dmode and G(h) (criterion (8)) and, for the implicit scheme, the exact modal
    coefficients and the driving-DOF response matrices."""
    step_matrices(h, p, w.dmode[slot], w.gmat[slot])
    if implicit:
        modal_coefficients(h, p.omega2, w.mcoef[slot])
        exact_matrices(p.phi_d, w.mcoef[slot], w.mmat[slot])


@njit(cache=True)
def held_friction(st, g, w):
    """Held friction of each plate contact from the Newton variables (implicit scheme):
    fguess[y] = mu (|N_n| + N_guess)/2 tanh(k_s v_guess)."""
    for k in range(g.pc_i.shape[0]):
        nbar = 0.5 * (st.normal[k] + max(w.fguess[2 * k], 0.0))
        w.fguess[2 * k + 1] = friction_magnitude(nbar, w.vguess[k], g.pc_coef[k, 2], g.pc_coef[k, 3])
        w.fbar[k] = w.fguess[2 * k + 1]


@njit(cache=True)
def held_friction_work(st, g, cfg, w):
    """Energy dissipated over the step by the held plate-contact friction [J], exactly:
    fbar times the slip displacement (dy_granule + a dtheta - du_plate,y), not a
    quadrature of fbar v_t (the plate's velocity may vibrate faster than the step)."""
    work = 0.0
    for k in range(g.pc_i.shape[0]):
        i = g.pc_i[k]
        dy = 2 * k + 1
        delta = w.ynew[i, 0] + g.radius[i] - (g.pc_x[k] + w.stage[2, 2 * k])
        arm = g.radius[i] - cfg.arm_shrink * max(delta, 0.0)
        slide = (w.ynew[i, 1] - st.y[i, 1]) + arm * (w.ynew[i, 2] - st.y[i, 2]) - (w.stage[2, dy] - st.u[dy])
        work += w.fbar[k] * slide
    return work


@njit(cache=True)
def newton_update(h, mmat, g, st, w):
    """One Newton step for the interface unknowns of the implicit scheme.

    The variables are, at every plate contact, the normal force's end value N and the
    end slip rate v; the held friction follows as mu (|N_n| + N)/2 tanh(k_s v)
    (held_friction), so it never leaves the friction cone and the stiff stick regime is
    solved in the slip rate, where the equation is mild. Residuals: N - N(delta, rate)
    and v - v_t after the step. The Jacobian is assembled from the contact laws'
    derivatives and the plate's exact response (mmat: u, v of the driving DOFs at t + h
    per unit force), so the contacts are coupled through the plate as they are
    physically; the granule's own response over the step enters on the diagonal (normal
    force linear over the step: h^2/(6 m), h/(2 m); held friction: h (1/m + R^2/I)). It
    is solved by Gaussian elimination with partial pivoting.
    """
    nd = w.fguess.shape[0]
    nk = g.pc_i.shape[0]
    jac = w.jac
    rhs = w.rhs
    # dF/dU of the contact laws, row by row, into jac (then chained with dU/dz)
    for k in range(nk):
        i = g.pc_i[k]
        dx = 2 * k
        dt_ = 2 * k + 1
        c = g.pc_coef[k]
        rhs[dx] = w.fnew[dx] - w.fguess[dx]
        rhs[dt_] = w.slip_new[k] - w.vguess[k]
        delta = w.ynew[i, 0] + g.radius[i] - (g.pc_x[k] + w.up[dx])
        n_d = 0.0  # dN/d(delta)
        n_v = 0.0  # dN/d(delta rate)
        if delta > 0.0 and w.normal_new[k] > 0.0:
            sq = math.sqrt(delta)
            n_d = 1.5 * c[0] * sq
            n_v = c[1] * math.sqrt(sq)
        inv_m = 1.0 / g.mass[i]
        inv_t = inv_m + g.radius[i] * g.radius[i] / g.inertia[i]
        for e in range(nd):
            ddel = -mmat[2, dx, e]
            drate = -mmat[3, dx, e]
            dvt = -mmat[3, dt_, e]
            if e == dx:
                ddel -= h * h * inv_m / 6.0
                drate -= 0.5 * h * inv_m
            if e == dt_:
                dvt -= h * inv_t
            jac[dx, e] = n_d * ddel + n_v * drate  # dN_k/dU_e
            jac[dt_, e] = dvt  # dv_k/dU_e
    # chain rule to the variables z = (N, v): dU_y/dN = phi_n, dU_y/dv = phi_v
    for j in range(nk):
        ch = math.cosh(g.pc_coef[j, 3] * w.vguess[j])
        nbar = 0.5 * (st.normal[j] + max(w.fguess[2 * j], 0.0))
        phi_v = g.pc_coef[j, 2] * nbar * g.pc_coef[j, 3] / (ch * ch)
        phi_n = 0.5 * g.pc_coef[j, 2] * math.tanh(g.pc_coef[j, 3] * w.vguess[j])
        for a in range(nd):
            dy_ = jac[a, 2 * j + 1]
            jac[a, 2 * j] = (1.0 if a == 2 * j else 0.0) - (jac[a, 2 * j] + dy_ * phi_n)
            jac[a, 2 * j + 1] = (1.0 if a == 2 * j + 1 else 0.0) - dy_ * phi_v
    # Gaussian elimination with partial pivoting: jac dz = rhs
    for col in range(nd):
        piv = col
        big = abs(jac[col, col])
        for r in range(col + 1, nd):
            if abs(jac[r, col]) > big:
                big = abs(jac[r, col])
                piv = r
        if big == 0.0:
            continue
        if piv != col:
            for b in range(nd):
                tmp = jac[col, b]
                jac[col, b] = jac[piv, b]
                jac[piv, b] = tmp
            tmp = rhs[col]
            rhs[col] = rhs[piv]
            rhs[piv] = tmp
        for r in range(col + 1, nd):
            fac = jac[r, col] / jac[col, col]
            if fac != 0.0:
                for b in range(col, nd):
                    jac[r, b] -= fac * jac[col, b]
                rhs[r] -= fac * rhs[col]
    for col in range(nd - 1, -1, -1):
        acc = rhs[col]
        for b in range(col + 1, nd):
            acc -= jac[col, b] * rhs[b]
        rhs[col] = acc / jac[col, col] if jac[col, col] != 0.0 else 0.0
    for k in range(nk):
        w.fguess[2 * k] += rhs[2 * k]
        w.vguess[k] += rhs[2 * k + 1]
    held_friction(st, g, w)


@njit(cache=True)
def step_error(ratio, st, g, cfg, w, nd):
    """Local error estimate of the implicit scheme (relative, ~ h^2 F''/2).

    The distance of the new interface forces and of the granules' net forces (m a, and
    I alpha / R for the rotation) from their linear extrapolation over the last two
    steps, relative to a force scale: the largest of these forces met so far, and at
    least `cfg.force_floor` (a fraction of the shock's peak force), so that the first
    touch of a contact is judged against the forces of the problem, not against itself.
    """
    sc = max(st.clock[F_SCALE], cfg.force_floor)
    err = 0.0
    for d in range(nd):
        u = w.fguess[d]
        sc = max(sc, abs(u))
        pred = st.force[d] + ratio * (st.force[d] - st.force_prev[d])
        err = max(err, abs(u - pred))
    for i in range(st.y.shape[0]):
        for c in range(3):
            m = g.mass[i] if c < 2 else g.inertia[i] / g.radius[i]
            sc = max(sc, m * abs(w.kend[i, 3 + c]))
            pred = st.k1[i, 3 + c] + ratio * (st.k1[i, 3 + c] - st.k0[i, 3 + c])
            err = max(err, m * abs(w.kend[i, 3 + c] - pred))
    st.clock[F_SCALE] = sc
    if sc <= 0.0:
        return 0.0
    return err / sc


@njit(cache=True)
def advance(t_stop, g, p, cfg, st, w, out):
    """Advance from st.clock[T_NOW] to t_stop (an output time). Returns a status code.

    On an error, st.err holds where and why (time, contact, |N|, slip, |lambda|, step,
    residual, iterations) and the state is the last accepted one.
    """
    nd = p.phi_d.shape[0]
    nk = g.pc_i.shape[0]
    ng = st.y.shape[0]
    n_out = out.t.shape[0]
    while st.clock[T_NOW] < t_stop - 1e-9 * cfg.dt_min:
        t = st.clock[T_NOW]
        o = st.count[C_OUT]
        if o >= n_out:
            return ERR_BUFFER
        t_out = out.target[o]
        implicit = cfg.scheme == SCHEME_IMPLICIT
        level = st.count[C_LEVEL]
        if implicit:
            level = dyadic_level(level, t - out.target[o - 1], cfg)
            st.count[C_LEVEL] = level
        h_lvl = level_step(level, cfg)
        rem = t_out - t
        slot = level
        land = False
        if implicit and abs(rem - h_lvl) <= 1e-9 * h_lvl:
            h = h_lvl  # the dyadic steps tile the output interval: land on the ladder
            land = True
        elif rem <= h_lvl * (1.0 + 1e-9):
            h = rem
            slot = N_LEVELS
            land = True
        elif rem < 2.0 * h_lvl:
            h = 0.5 * rem
            slot = N_LEVELS
        else:
            h = h_lvl
        if slot == N_LEVELS:
            if st.clock[CUSTOM_H] != h:
                level_matrices(h, implicit, p, w, N_LEVELS)
                st.clock[CUSTOM_H] = h
        elif w.g_ok[slot] == 0:
            level_matrices(h, implicit, p, w, slot)
            w.g_ok[slot] = 1
        gm = w.gmat[slot]
        dm = w.dmode[slot]
        if implicit:
            exact_predict(t, h, st, p, cfg, w.mcoef[slot], w)
        else:
            newmark_predict(t, h, st, p, cfg, dm, w.qdd_star, w.astar)
        # first guess: linear extrapolation of the interface forces
        ratio = h / st.clock[H_LAST] if st.clock[H_LAST] > 0.0 else 0.0
        for d in range(nd):
            w.fguess[d] = st.force[d] + ratio * (st.force[d] - st.force_prev[d])
        for k in range(nk):
            w.conv_iter[k] = 0
        converged = False
        e_pot = 0.0
        rate = 0.0
        it = 0
        worst = -1
        if implicit:
            for k in range(nk):
                w.vguess[k] = st.slip[k]
            held_friction(st, g, w)
        while it < cfg.max_iter:
            it += 1
            if implicit:
                stage_motion_exact(w.mmat[slot], w)
            else:
                for d in range(nd):
                    s = w.astar[d]
                    for e in range(nd):
                        s += gm[d, e] * w.fguess[e]
                    w.anext[d] = s
                    w.aavg[d] = 0.5 * (st.a[d] + s)
                stage_motion_newmark(h, st, w)
            e_pot, rate = rk4_granular_step(t, h, st, g, cfg, w)
            converged = True
            worst = -1
            worst_err = 0.0
            for k in range(nk):
                for c in range(2):
                    d = 2 * k + c
                    diff = abs(w.fnew[d] - w.fguess[d])
                    if diff > cfg.rtol * abs(w.fnew[d]) + cfg.atol:
                        converged = False
                        w.conv_iter[k] = it + 1
                        if diff > worst_err:
                            worst_err = diff
                            worst = k
            if converged:
                break
            if implicit:
                newton_update(h, w.mmat[slot], g, st, w)
            else:
                for d in range(nd):
                    w.fguess[d] = w.fnew[d]
        st.count[C_ITERS] += it
        if not converged:
            st.count[C_RETRIES] += 1
            new_level = level + 4
            if level_step(new_level, cfg) < cfg.dt_min or new_level >= N_LEVELS:
                st.err[ERR_T] = t
                st.err[ERR_CONTACT] = worst
                st.err[ERR_N] = w.normal_new[worst] if worst >= 0 else 0.0
                st.err[ERR_VT] = w.slip_new[worst] if worst >= 0 else 0.0
                st.err[ERR_LAM] = 0.0
                if worst >= 0:
                    st.err[ERR_LAM] = local_map_modulus(
                        g.pc_coef[worst, 2], g.pc_coef[worst, 3], w.normal_new[worst], h,
                        gm[2 * worst + 1, 2 * worst + 1], w.slip_new[worst])
                st.err[ERR_H] = h
                st.err[ERR_ITER] = it
                return ERR_NOCONV
            st.count[C_LEVEL] = new_level
            continue
        err = 0.0
        if implicit:
            # the end state, not yet committed: the step may still be refused
            fric_work = held_friction_work(st, g, cfg, w)
            work, ep_new = exact_correct(t, h, st, p, cfg, w.mcoef[slot], w.fguess, w.qn, w.qdn)
            kx, ky, kr = kinetic_energies(w.ynew, g)
            e_in = st.clock[E_ZERO] + st.acc[A_SHOCK_G] + w.dacc[0] + st.acc[A_SHOCK_P] + work
            total = (kx + ky + kr + e_pot + ep_new + st.acc[A_VISC] + w.dacc[1]
                     + st.acc[A_FRIC] + w.dacc[2] + fric_work)
            denom = max(st.clock[E_IN_MAX], e_in)
            d_res = 0.0
            if denom > 0.0 and math.isfinite(total):
                d_res = (total - e_in) / denom - st.clock[RES_LAST]
            err = step_error(ratio, st, g, cfg, w, nd) / cfg.error_tol
            # the energy residual may grow by energy_tol * ENERGY_STEP_FRACTION over the run
            if not (cfg.q0 != 0.0 and t < cfg.duration):  # (E_in ~ 0 while the shock starts)
                # each step may add to the energy residual its share of
                # energy_tol * ENERGY_STEP_FRACTION, the run counted in steps of dt_max
                err = max(err, abs(d_res) * cfg.t_end / (cfg.energy_tol * ENERGY_STEP_FRACTION * cfg.dt_max))
            if err > REJECT_FACTOR and st.clock[H_LAST] > 0.0:
                # too large an error: retry the step smaller (nothing was committed)
                new_level = max(level_for(h * max(0.2, 0.9 / math.sqrt(err)), cfg), level + 1)
                if level_step(new_level, cfg) >= cfg.dt_min and new_level < N_LEVELS:
                    st.count[C_RETRIES] += 1
                    st.count[C_LEVEL] = new_level
                    continue
        # accept: the plate moves with the forces the granules saw (w.fguess)
        if implicit:
            w.dacc[2] += fric_work
            for m in range(p.omega2.shape[0]):
                st.q[m] = w.qn[m]
                st.qd[m] = w.qdn[m]
            for d in range(nd):
                st.u[d] = w.stage[2, d]
                st.v[d] = w.stage[3, d]
                st.a[d] = 0.0  # not used by the modal integration of this scheme
                st.pforce[d] = w.fguess[d]
                st.force_prev[d] = st.force[d]
                st.force[d] = w.fguess[d]
        else:
            work = newmark_correct(t, h, st, p, cfg, dm, w.qdd_star, w.fguess)
            for d in range(nd):
                s = w.astar[d]
                for e in range(nd):
                    s += gm[d, e] * w.fguess[e]
                a1 = s
                v1 = st.v[d] + 0.5 * h * (st.a[d] + a1)
                st.u[d] = st.u[d] + h * st.v[d] + 0.25 * h * h * (st.a[d] + a1)
                st.v[d] = v1
                st.a[d] = a1
                st.pforce[d] = w.fguess[d]
                st.force_prev[d] = st.force[d]
                st.force[d] = w.fnew[d]
        for i in range(ng):
            for c in range(6):
                st.y[i, c] = w.ynew[i, c]
                st.k0[i, c] = st.k1[i, c]
                st.k1[i, c] = w.kend[i, c]
        st.p1[0] = w.pend[0]
        st.p1[1] = w.pend[1]
        st.p1[2] = w.pend[2]
        st.acc[A_SHOCK_G] += w.dacc[0]
        st.acc[A_VISC] += w.dacc[1]
        st.acc[A_FRIC] += w.dacc[2]
        st.acc[A_SHOCK_P] += work
        st.clock[E_POT] = e_pot
        st.clock[T_NOW] = t_out if land else t + h
        st.clock[H_LAST] = h
        st.count[C_STEPS] += 1
        w.dt_int[0] = min(w.dt_int[0], h)
        w.dt_int[1] = max(w.dt_int[1], h)
        # criterion (8) at every plate contact, and the next step
        lam_max = 0.0
        for k in range(nk):
            st.normal[k] = w.normal_new[k]
            st.slip[k] = w.slip_new[k]
            lam = local_map_modulus(g.pc_coef[k, 2], g.pc_coef[k, 3], st.normal[k], h,
                                    gm[2 * k + 1, 2 * k + 1], st.slip[k])
            w.lam_int[k] = max(w.lam_int[k], lam)
            w.it_int[k] = max(w.it_int[k], w.conv_iter[k] if w.conv_iter[k] > 0 else 1)
            lam_max = max(lam_max, lam)
        if implicit:
            grow = 2.0 if err <= 0.0 else min(2.0, max(0.3, 0.9 / math.sqrt(err)))
            h_new = min(max(h, h_lvl if slot == N_LEVELS else h) * grow, cfg.dt_max)
        elif lam_max > 0.0:
            h_new = min(h * cfg.lambda_target / lam_max, 2.0 * h_lvl, cfg.dt_max)
        else:
            h_new = min(2.0 * h_lvl, cfg.dt_max)
        if rate * h_new > RK4_FRICTION_LIMIT:
            h_new = RK4_FRICTION_LIMIT / rate
        if implicit and cfg.q0 != 0.0 and st.clock[T_NOW] < cfg.duration:
            # resolve the shock pulse itself (its work is a quadrature over the steps)
            h_new = min(h_new, cfg.duration / SHOCK_STEPS)
        new_level = level_for(h_new, cfg)
        if implicit and level_step(new_level, cfg) < cfg.dt_min:
            new_level = level_for(cfg.dt_min, cfg) - 1  # accuracy, not stability: go on at dt_min
        if level_step(new_level, cfg) < cfg.dt_min:
            st.err[ERR_T] = st.clock[T_NOW]
            kw = 0
            for k in range(nk):
                if w.lam_int[k] >= w.lam_int[kw]:
                    kw = k
            st.err[ERR_CONTACT] = kw
            st.err[ERR_N] = st.normal[kw]
            st.err[ERR_VT] = st.slip[kw]
            st.err[ERR_LAM] = lam_max
            st.err[ERR_H] = h_new
            st.err[ERR_ITER] = it
            return ERR_NOCONV
        st.count[C_LEVEL] = new_level
        # energy balance at every step
        eshock, eg, ep, kx, ky, kr = energy_balance(st, g, p)
        e_in = st.clock[E_ZERO] + eshock
        if e_in > st.clock[E_IN_MAX]:
            st.clock[E_IN_MAX] = e_in
        total = eg + ep + st.acc[A_VISC] + st.acc[A_FRIC]
        if not (math.isfinite(total) and math.isfinite(e_in)):
            st.err[ERR_T] = st.clock[T_NOW]
            st.err[ERR_H] = h
            return ERR_NAN
        denom = st.clock[E_IN_MAX]
        if denom > 0.0:
            res = (total - e_in) / denom
            st.clock[RES_LAST] = res
            if abs(res) > w.res_int[0]:
                w.res_int[0] = abs(res)
            if abs(res) > cfg.energy_tol:
                st.err[ERR_T] = st.clock[T_NOW]
                st.err[ERR_RESID] = res
                st.err[ERR_H] = h
                return ERR_ENERGY
        if land:
            record(o, st, g, p, w, out)
            st.count[C_OUT] = o + 1
    return OK


def new_state(ng: int, nm: int, nk: int) -> State:
    """A zeroed State for ng granules, nm modes and nk plate contacts."""
    nd = 2 * nk
    z = np.zeros
    return State(
        y=z((ng, 6)), acc=z(N_ACC), q=z(nm), qd=z(nm), qdd=z(nm), u=z(nd), v=z(nd),
        a=z(nd), force=z(nd), force_prev=z(nd), k1=z((ng, 6)), k0=z((ng, 6)), pforce=z(nd),
        p1=z(3), normal=z(nk),
        slip=z(nk), clock=z(N_CLOCK), count=np.zeros(N_COUNT, np.int64), err=z(N_ERR),
    )


def new_work(ng: int, nm: int, nk: int, exact: bool = False) -> Work:
    """Scratch arrays for the loop (exact: room for the implicit scheme's per-level
    modal coefficients)."""
    nd = 2 * nk
    z = np.zeros
    return Work(
        ytmp=z((ng, 6)), ynew=z((ng, 6)), k2=z((ng, 6)), k3=z((ng, 6)), k4=z((ng, 6)),
        kend=z((ng, 6)), up=z(nd), vp=z(nd), astar=z(nd), anext=z(nd), aavg=z(nd),
        fguess=z(nd), stage=z((4, nd)), ustar=z((4, nd)), qn=z(nm), qdn=z(nm), jac=z((nd, nd)), rhs=z(nd), vguess=z(nk),
        mcoef=z((N_LEVELS + 1 if exact else 1, nm if exact else 1, N_MCOEF)),
        mmat=z((N_LEVELS + 1 if exact else 1, 4, nd, nd)), fbar=z(nk), k1i=z((ng, 6)), p1i=z(3), fnew=z(nd), fscratch=z(nd), pend=z(3), dacc=z(3), qdd_star=z(nm),
        normal_new=z(nk), slip_new=z(nk), nscratch=z(nk), sscratch=z(nk),
        conv_iter=np.zeros(nk, np.int64), dmode=z((N_LEVELS + 1, nm)),
        gmat=z((N_LEVELS + 1, nd, nd)), g_ok=np.zeros(N_LEVELS + 1, np.int64),
        lam_int=z(nk), it_int=np.zeros(nk, np.int64), dt_int=z(2), res_int=z(1),
    )


def new_output(times: np.ndarray, ng: int, nm: int, nk: int) -> Output:
    """Output buffers for the given output times."""
    z = np.zeros
    n_out = len(times)
    return Output(
        target=np.asarray(times, float).copy(), t=z(n_out), y=z((n_out, ng, 6)), energy=z((n_out, N_ENERGY)), q=z((n_out, nm)),
        qd=z((n_out, nm)), force=z((n_out, nk, 2)), slip=z((n_out, nk)), lam=z((n_out, nk)),
        iters=np.zeros((n_out, nk), np.int64), stats=z((n_out, N_STEPSTAT)),
    )

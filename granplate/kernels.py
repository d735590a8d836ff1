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
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from .contact import contact_response, local_map_modulus
from .shock import time_profile

# --- layout of the small bookkeeping arrays -------------------------------------------
# clock (float64)
T_NOW, H_LAST, E_IN_MAX, E_ZERO, E_POT, CUSTOM_H, F_SCALE = 0, 1, 2, 3, 4, 5, 6
A_SCALE = 7  # 3 slots: 7, 8, 9
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
    pvec: np.ndarray  # (nd,) plate end forces of the step being solved
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
            pf = f * vt
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
def contact_point_motion(s, u0, v0, aavg, up, vp):
    """Driving-DOF motion inside a Newmark step (constant average acceleration).

    u(s) = u0 + v0 s + aavg s^2 / 2, v(s) = v0 + aavg s; at s = h this is exactly
    Newmark's average-acceleration update (the interpolation of the paper's scheme).
    """
    for d in range(u0.shape[0]):
        up[d] = u0[d] + v0[d] * s + 0.5 * aavg[d] * s * s
        vp[d] = v0[d] + aavg[d] * s


@njit(cache=True)
def rk4_granular_step(t, h, st, g, cfg, w):
    """One RK4 step of the granules with the contact points moving as w.aavg says.

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
    contact_point_motion(hh, st.u, st.v, w.aavg, w.up, w.vp)
    for i in range(ng):
        for c in range(6):
            w.ytmp[i, c] = y0[i, c] + hh * k1[i, c]
    p2 = granular_rhs(t + hh, w.ytmp, w.up, w.vp, g, cfg, w.k2, w.fscratch, w.nscratch, w.sscratch, hold, w.fbar)
    for i in range(ng):
        for c in range(6):
            w.ytmp[i, c] = y0[i, c] + hh * w.k2[i, c]
    p3 = granular_rhs(t + hh, w.ytmp, w.up, w.vp, g, cfg, w.k3, w.fscratch, w.nscratch, w.sscratch, hold, w.fbar)
    contact_point_motion(h, st.u, st.v, w.aavg, w.up, w.vp)
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
    w.pend[0] = pe[0]
    w.pend[1] = pe[1]
    w.pend[2] = pe[2]
    return pe[3], pe[4]


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
def level_for(h, cfg):
    """Smallest ladder level whose step does not exceed h."""
    if h >= cfg.dt_max:
        return 0
    lv = int(math.ceil(math.log(h / cfg.dt_max) / math.log(LEVEL_RATIO) - 1e-9))
    return min(max(lv, 0), N_LEVELS - 1)


# --- the loop -----------------------------------------------------------------------------


@njit(cache=True)
def plate_end_forces(implicit, st, w):
    """The plate's end force P_n+1 from the unknowns w.fguess.

    paper: P = F_n+1 (Newmark's trapezoid averages F_n and F_n+1). implicit: normal
    forces the same; the friction fbar is held over the whole step for the plate and the
    granule alike (backward Euler for the stiff friction, L-stable: no stick chatter),
    which in Newmark's trapezoid is the end force P = 2 fbar - P_n.
    """
    nd = w.fguess.shape[0]
    for d in range(nd):
        if implicit and d % 2 == 1:
            w.fbar[d // 2] = w.fguess[d]
            w.pvec[d] = 2.0 * w.fguess[d] - st.pforce[d]
        else:
            w.pvec[d] = w.fguess[d]


@njit(cache=True)
def newton_update(h, gm, g, w):
    """One diagonal Newton step on r = U - F(U) at every plate contact (implicit scheme).

    Normal: dF/dU = -3/2 A delta^1/2 (h^2/4) G_xx (the plate yields under the force);
    friction: dF/dU = -mu |N| k_s cosh^-2(k_s v_t) h (G_yy + 1/m + a^2/I) (the held force
    changes the plate's and the granule's tangential velocity).
    """
    for k in range(g.pc_i.shape[0]):
        i = g.pc_i[k]
        dx = 2 * k
        dt_ = 2 * k + 1
        delta = w.ynew[i, 0] + g.radius[i] - (g.pc_x[k] + w.up[dx])
        jac = 1.0
        if delta > 0.0:
            jac += 1.5 * g.pc_coef[k, 0] * math.sqrt(delta) * 0.25 * h * h * gm[dx, dx]
        w.fguess[dx] -= (w.fguess[dx] - w.fnew[dx]) / jac
        n = w.normal_new[k]
        ch = math.cosh(g.pc_coef[k, 3] * w.slip_new[k])
        jt = 1.0 + g.pc_coef[k, 2] * n * g.pc_coef[k, 3] / (ch * ch) * h * (
            gm[dt_, dt_] + 1.0 / g.mass[i] + g.radius[i] ** 2 / g.inertia[i])
        w.fguess[dt_] -= (w.fguess[dt_] - w.fnew[dt_]) / jt


@njit(cache=True)
def step_error(ratio, st, w, nd):
    """Local error estimate of the implicit scheme (relative, ~ h^2 f''/2).

    The distance of the new interface forces and granule accelerations from their linear
    extrapolation over the last two steps, relative to the largest values met so far.
    """
    err = 0.0
    for d in range(nd):
        u = w.fguess[d]
        st.clock[F_SCALE] = max(st.clock[F_SCALE], abs(u))
        pred = st.force[d] + ratio * (st.force[d] - st.force_prev[d])
        err = max(err, abs(u - pred))
    err = err / max(st.clock[F_SCALE], 1e-300)
    for c in range(3):
        sc = st.clock[A_SCALE + c]
        for i in range(st.y.shape[0]):
            sc = max(sc, abs(w.kend[i, 3 + c]))
        st.clock[A_SCALE + c] = sc
        if sc > 0.0:
            for i in range(st.y.shape[0]):
                pred = st.k1[i, 3 + c] + ratio * (st.k1[i, 3 + c] - st.k0[i, 3 + c])
                err = max(err, abs(w.kend[i, 3 + c] - pred) / sc)
    return err


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
        level = st.count[C_LEVEL]
        h_lvl = level_step(level, cfg)
        rem = t_out - t
        slot = level
        land = False
        if rem <= h_lvl * (1.0 + 1e-9):
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
                step_matrices(h, p, w.dmode[N_LEVELS], w.gmat[N_LEVELS])
                st.clock[CUSTOM_H] = h
        elif w.g_ok[slot] == 0:
            step_matrices(h, p, w.dmode[slot], w.gmat[slot])
            w.g_ok[slot] = 1
        gm = w.gmat[slot]
        dm = w.dmode[slot]
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
        implicit = cfg.scheme == SCHEME_IMPLICIT
        while it < cfg.max_iter:
            it += 1
            plate_end_forces(implicit, st, w)
            for d in range(nd):
                s = w.astar[d]
                for e in range(nd):
                    s += gm[d, e] * w.pvec[e]
                w.anext[d] = s
                w.aavg[d] = 0.5 * (st.a[d] + s)
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
                newton_update(h, gm, g, w)
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
        # accept: the plate moves with the forces the granules saw (w.pvec)
        work = newmark_correct(t, h, st, p, cfg, dm, w.qdd_star, w.pvec)
        err = 0.0
        if implicit:
            err = step_error(ratio, st, w, nd)
        for d in range(nd):
            s = w.astar[d]
            for e in range(nd):
                s += gm[d, e] * w.pvec[e]
            a1 = s
            v1 = st.v[d] + 0.5 * h * (st.a[d] + a1)
            st.u[d] = st.u[d] + h * st.v[d] + 0.25 * h * h * (st.a[d] + a1)
            st.v[d] = v1
            st.a[d] = a1
            st.pforce[d] = w.pvec[d]
            st.force_prev[d] = st.force[d]
            st.force[d] = w.fguess[d] if implicit else w.fnew[d]
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
            grow = 2.0 if err <= 0.0 else min(2.0, max(0.3, 0.9 * math.sqrt(cfg.error_tol / err)))
            h_new = min(max(h, h_lvl if slot == N_LEVELS else h) * grow, cfg.dt_max)
        elif lam_max > 0.0:
            h_new = min(h * cfg.lambda_target / lam_max, 2.0 * h_lvl, cfg.dt_max)
        else:
            h_new = min(2.0 * h_lvl, cfg.dt_max)
        if rate * h_new > RK4_FRICTION_LIMIT:
            h_new = RK4_FRICTION_LIMIT / rate
        new_level = level_for(h_new, cfg)
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


def new_work(ng: int, nm: int, nk: int) -> Work:
    """Scratch arrays for the loop."""
    nd = 2 * nk
    z = np.zeros
    return Work(
        ytmp=z((ng, 6)), ynew=z((ng, 6)), k2=z((ng, 6)), k3=z((ng, 6)), k4=z((ng, 6)),
        kend=z((ng, 6)), up=z(nd), vp=z(nd), astar=z(nd), anext=z(nd), aavg=z(nd),
        fguess=z(nd), pvec=z(nd), fbar=z(nk), k1i=z((ng, 6)), p1i=z(3), fnew=z(nd), fscratch=z(nd), pend=z(3), dacc=z(3), qdd_star=z(nm),
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

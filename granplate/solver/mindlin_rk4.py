"""Mindlin's tangential law in the RK4 stages of the schemes "paper" and "implicit"
(docs/model.md section 3.16, "Under RK4"), in the plane and in space.

The law's history xi (per contact) is a state of the step, like the largest overlap of a
yielding law: every stage evaluates the spring from the committed history (HIST_XI at the
contact radius HIST_A of the step's start), rescaled and turned into the stage's tangent
plane (eqs. M2-M3), moved on by the slip the stage's RK4 formula gives it, and capped
(eqs. M4-M5, physics.mindlin.stage_force). The elastic displacement is thus integrated as
extra unknowns of RK4, d xi / dt = v_s, with the Coulomb cap as a projection:

    stage 1 at t:        xi_1 = xi_n                          (its slip v_1)
    stage 2 at t + h/2:  xi_2 = xi_n + h/2 v_1
    stage 3 at t + h/2:  xi_3 = xi_n + h/2 v_2
    stage 4 at t + h:    xi_4 = xi_n + h v_3
    end:                 xi_n+1 = xi_n + h/6 (v_1 + 2 v_2 + 2 v_3 + v_4), capped at the end state

The trial columns of the contact's history carry the stage's data while the step runs
(HIST_A_END < 0 marks it; the force pass of the end writes the trial history proper, which
the loop commits when it accepts the step): HIST_XI_END the running sum of the stages'
slip velocities with RK4's weights, HIST_F_END the increment the next stage adds, then that
stage's slip velocity. A force pass outside a step (HIST_A_END >= 0: the run's first pass,
a patch contact's move) takes the force of the committed history at its state.

Energy (eq. 11): each stage's dissipated power -F_t . v_s goes with the friction power into
RK4's quadrature; the step's end takes the rise of the springs' energy out of it
(`spring_rise`), as the springs' energy is in E_g.
"""

from __future__ import annotations

import math

from granplate.jit import njit

from granplate.model.inputs import HIST_A, HIST_A_END, HIST_F_END, HIST_MAX, HIST_RATE, HIST_XI, HIST_XI_END, N_MINDLIN
from granplate.physics.contact import (
    contact_arm,
    pair_apart,
    pair_overlap,
    pair_rates,
    plate_overlap,
    wall_overlap,
    wall_rates,
)
from granplate.physics.laws import (
    keeps_history,
    normal_law_force,
    tangential_energy,
    tangential_scale,
    tangential_stage,
    tangential_stiffness,
)
from granplate.solver.mindlin_history import record_trial
from granplate.physics.space import arm_torque_3d, normal_rate_3d, pair_contact_3d, slip_velocity_3d, wall_overlap_3d
from granplate.solver.drives import wall_motion


@njit(cache=True)
def stage_contact(hist, k, c, a, delta, nx, ny, nz, vx, vy, vz, n_abs, record):
    """Contact k (history row hist[k], coefficient row c) in touch at a force pass: its
    overlap delta and contact radius a [m], unit normal n, slip velocity v (3) [m/s] and
    |N| = n_abs [N]. Inside an RK4 step (HIST_A_END < 0) the committed history moved on by
    the stage's increment (HIST_F_END), and the slip velocity left in HIST_F_END for the
    next stage; record: the result into the trial history (HIST_XI_END, HIST_A_END,
    HIST_F_END). Returns (F_t (3) on the first body [N], the spring's energy [J])."""
    staged = hist[k, HIST_A_END] < 0.0
    ix = 0.0
    iy = 0.0
    iz = 0.0
    if staged:
        ix = hist[k, HIST_F_END]
        iy = hist[k, HIST_F_END + 1]
        iz = hist[k, HIST_F_END + 2]
    fx, fy, fz, xx, xy, xz, e = tangential_stage(
        hist[k, HIST_XI],
        hist[k, HIST_XI + 1],
        hist[k, HIST_XI + 2],
        a,
        hist[k, HIST_A],
        c,
        delta,
        nx,
        ny,
        nz,
        ix,
        iy,
        iz,
        vx,
        vy,
        vz,
        abs(n_abs),
    )
    if record:
        record_trial(hist, k, xx, xy, xz, a, fx, fy, fz)
    elif staged:
        hist[k, HIST_F_END] = vx
        hist[k, HIST_F_END + 1] = vy
        hist[k, HIST_F_END + 2] = vz
    return fx, fy, fz, e


@njit(cache=True)
def stage_apart(hist, k, record):
    """Contact k out of touch at a force pass: no slip for the next stage; record: its
    trial history zero (a new touch starts unloaded; the spring's energy is lost)."""
    if record:
        for col in range(N_MINDLIN):
            hist[k, HIST_XI_END + col] = 0.0
    elif hist[k, HIST_A_END] < 0.0:
        for col in range(3):
            hist[k, HIST_F_END + col] = 0.0


@njit(cache=True)
def sticking_rate(kt, inv_mass) -> float:
    """The sticking contact's angular frequency sqrt(k_t / m_t) [1/s] (k_t [N/m], 1 / m_t =
    inv_mass [1/kg], the tangential inverse mass with the spins'): RK4 stays stable and
    accurate on it where h times it stays within solver.rk4.RK4_FRICTION_LIMIT."""
    return math.sqrt(kt * inv_mass)


@njit(cache=True)
def plane_stages(y, dy, g, cfg, record, p_fric, e_pot, rate):
    """The history law (Mindlin's) at the plane's pair and wall contacts whose tangential
    law keeps a history (laws.keeps_history), at state y: the forces and torques added to
    dy (forces, not yet divided by the masses), the dissipated power -F_t . v_s to p_fric [W], the springs' energy to
    e_pot [J], the sticking rate to rate [1/s]; record: the trial histories. Returns
    (p_fric, e_pot, rate)."""
    half_shrink = 0.5 * cfg.arm_shrink
    hist = g.pair_hist
    for p in range(g.pair_ij.shape[0]):
        c = g.pair_coef[p]
        if not keeps_history(c):
            continue
        i = g.pair_ij[p, 0]
        j = g.pair_ij[p, 1]
        ri = g.radius[i]
        rj = g.radius[j]
        delta = -1.0
        nx = 0.0
        nz = 0.0
        if not pair_apart(y[i, 0], y[i, 1], ri, y[j, 0], y[j, 1], rj):
            delta, nx, nz = pair_overlap(y[i, 0], y[i, 1], ri, y[j, 0], y[j, 1], rj)
        if delta <= 0.0:
            stage_apart(hist, p, record)
            continue
        ai = contact_arm(ri, delta, half_shrink)
        aj = contact_arm(rj, delta, half_shrink)
        ddot, vt = pair_rates(y[i, 3], y[i, 4], y[i, 5], y[j, 3], y[j, 4], y[j, 5], nx, nz, ai, aj)
        n = normal_law_force(delta, ddot, c, hist[p, HIST_MAX], hist[p, HIST_RATE], cfg.clip)
        a = tangential_scale(c, ri * rj / (ri + rj), delta)
        fx, fy, _, e = stage_contact(hist, p, c, a, delta, nx, nz, 0.0, -vt * nz, vt * nx, 0.0, n, record)
        tq = nx * fy - nz * fx  # F_t . t, t = (-n_z, n_x)
        dy[i, 3] += fx
        dy[i, 4] += fy
        dy[j, 3] -= fx
        dy[j, 4] -= fy
        dy[i, 5] += ai * tq
        dy[j, 5] += aj * tq
        p_fric -= tq * vt
        e_pot += e
        inv_m = 1.0 / g.mass[i] + 1.0 / g.mass[j] + ai * ai / g.inertia[i] + aj * aj / g.inertia[j]
        rate = max(rate, sticking_rate(tangential_stiffness(c, a), inv_m))
    hist = g.wall_hist
    for w in range(g.wall_i.shape[0]):
        c = g.wall_coef[w]
        if not keeps_history(c):
            continue
        i = g.wall_i[w]
        ri = g.radius[i]
        nx = g.wall_geo[w, 0]
        nz = g.wall_geo[w, 1]
        shift, vn, _ = wall_motion(g, w)
        delta = wall_overlap(y[i, 0], y[i, 1], ri, nx, nz, g.wall_geo[w, 2] + shift)
        if delta <= 0.0:
            stage_apart(hist, w, record)
            continue
        arm = contact_arm(ri, delta, cfg.arm_shrink)
        ddot, vt = wall_rates(y[i, 3], y[i, 4], y[i, 5], nx, nz, arm)
        n = normal_law_force(delta, ddot - vn, c, hist[w, HIST_MAX], hist[w, HIST_RATE], cfg.clip)
        a = tangential_scale(c, ri, delta)
        fx, fy, _, e = stage_contact(hist, w, c, a, delta, nx, nz, 0.0, -vt * nz, vt * nx, 0.0, n, record)
        tq = nx * fy - nz * fx
        dy[i, 3] += fx
        dy[i, 4] += fy
        dy[i, 5] += arm * tq
        p_fric -= tq * vt
        e_pot += e
        rate = max(rate, sticking_rate(tangential_stiffness(c, a), 1.0 / g.mass[i] + arm * arm / g.inertia[i]))
    return p_fric, e_pot, rate


@njit(cache=True)
def plate_stages(y, up, g, cfg, record, dy, fplate, normal, slip, p_fric, e_pot, rate):
    """The history law (Mindlin's) at the plane's plate contacts whose tangential law keeps
    a history, after the plate-contact pass of `solver.granular.granular_rhs` (its |N| in
    normal, its slip rates v_t = v_y - v_edge,y + a omega in slip; up the driving DOFs'
    displacement): n = (1, 0) into the plate, t = (0, 1); F_t on the granule into dy (forces,
    not yet divided by the masses) with its torque a F_t, -F_t on the plate into fplate's
    odd entries; -F_t v_t to p_fric [W], the springs' energy to e_pot [J], the sticking rate
    to rate [1/s]; record: the trial histories. Returns (p_fric, e_pot, rate)."""
    hist = g.pc_hist
    for k in range(g.pc_i.shape[0]):
        c = g.pc_coef[k]
        if not keeps_history(c):
            continue
        i = g.pc_i[k]
        ri = g.radius[i]
        delta = plate_overlap(y[i, 0], ri, g.pc_x[k] + up[2 * k])
        if delta <= 0.0:
            stage_apart(hist, k, record)
            continue
        arm = contact_arm(ri, delta, cfg.arm_shrink)
        vt = slip[k]
        a = tangential_scale(c, ri, delta)
        _, fy, _, e = stage_contact(hist, k, c, a, delta, 1.0, 0.0, 0.0, 0.0, vt, 0.0, normal[k], record)
        dy[i, 4] += fy
        dy[i, 5] += arm * fy
        fplate[2 * k + 1] -= fy
        p_fric -= fy * vt
        e_pot += e
        rate = max(rate, sticking_rate(tangential_stiffness(c, a), 1.0 / g.mass[i] + arm * arm / g.inertia[i]))
    return p_fric, e_pot, rate


@njit(cache=True)
def push_space(dy, i, a, nx, ny, nz, fx, fy, fz, sign):
    """sign * F [N] on granule i's velocity columns of dy and its torque a n x F [N m] on
    the spin columns (the torque's sign the same on both bodies of a pair)."""
    dy[i, 3] += sign * fx
    dy[i, 4] += sign * fy
    dy[i, 5] += sign * fz
    tx, ty, tz = arm_torque_3d(a, nx, ny, nz, fx, fy, fz)
    dy[i, 6] += tx
    dy[i, 7] += ty
    dy[i, 8] += tz


@njit(cache=True)
def space_stages(y, dy, g, cfg, record, p_fric, e_pot, rate):
    """`plane_stages` in space (state x, y, z, vx, vy, vz, wx, wy, wz)."""
    half_shrink = 0.5 * cfg.arm_shrink
    hist = g.pair_hist
    for p in range(g.pair_ij.shape[0]):
        c = g.pair_coef[p]
        if not keeps_history(c):
            continue
        i = g.pair_ij[p, 0]
        j = g.pair_ij[p, 1]
        ri = g.radius[i]
        rj = g.radius[j]
        delta, nx, ny, nz = pair_contact_3d(y[i, 0], y[i, 1], y[i, 2], ri, y[j, 0], y[j, 1], y[j, 2], rj)
        if delta <= 0.0:
            stage_apart(hist, p, record)
            continue
        ai = contact_arm(ri, delta, half_shrink)
        aj = contact_arm(rj, delta, half_shrink)
        rvx = y[i, 3] - y[j, 3]
        rvy = y[i, 4] - y[j, 4]
        rvz = y[i, 5] - y[j, 5]
        sx = ai * y[i, 6] + aj * y[j, 6]
        sy = ai * y[i, 7] + aj * y[j, 7]
        sz = ai * y[i, 8] + aj * y[j, 8]
        vx, vy, vz = slip_velocity_3d(rvx, rvy, rvz, sx, sy, sz, nx, ny, nz)
        ddot = normal_rate_3d(rvx, rvy, rvz, nx, ny, nz)
        n = normal_law_force(delta, ddot, c, hist[p, HIST_MAX], hist[p, HIST_RATE], cfg.clip)
        a = tangential_scale(c, ri * rj / (ri + rj), delta)
        fx, fy, fz, e = stage_contact(hist, p, c, a, delta, nx, ny, nz, vx, vy, vz, n, record)
        push_space(dy, i, ai, nx, ny, nz, fx, fy, fz, 1.0)
        push_space(dy, j, aj, nx, ny, nz, fx, fy, fz, -1.0)
        p_fric -= fx * vx + fy * vy + fz * vz
        e_pot += e
        inv_m = 1.0 / g.mass[i] + 1.0 / g.mass[j] + ai * ai / g.inertia[i] + aj * aj / g.inertia[j]
        rate = max(rate, sticking_rate(tangential_stiffness(c, a), inv_m))
    hist = g.wall_hist
    for w in range(g.wall_i.shape[0]):
        c = g.wall_coef[w]
        if not keeps_history(c):
            continue
        i = g.wall_i[w]
        ri = g.radius[i]
        nx = g.wall_geo[w, 0]
        ny = g.wall_geo[w, 1]
        nz = g.wall_geo[w, 2]
        shift, vn, _ = wall_motion(g, w)
        delta = wall_overlap_3d(y[i, 0], y[i, 1], y[i, 2], ri, nx, ny, nz, g.wall_geo[w, 3] + shift)
        if delta <= 0.0:
            stage_apart(hist, w, record)
            continue
        arm = contact_arm(ri, delta, cfg.arm_shrink)
        sx = arm * y[i, 6]
        sy = arm * y[i, 7]
        sz = arm * y[i, 8]
        vx, vy, vz = slip_velocity_3d(y[i, 3], y[i, 4], y[i, 5], sx, sy, sz, nx, ny, nz)
        ddot = normal_rate_3d(y[i, 3], y[i, 4], y[i, 5], nx, ny, nz) - vn
        n = normal_law_force(delta, ddot, c, hist[w, HIST_MAX], hist[w, HIST_RATE], cfg.clip)
        a = tangential_scale(c, ri, delta)
        fx, fy, fz, e = stage_contact(hist, w, c, a, delta, nx, ny, nz, vx, vy, vz, n, record)
        push_space(dy, i, arm, nx, ny, nz, fx, fy, fz, 1.0)
        p_fric -= fx * vx + fy * vy + fz * vz
        e_pot += e
        rate = max(rate, sticking_rate(tangential_stiffness(c, a), 1.0 / g.mass[i] + arm * arm / g.inertia[i]))
    return p_fric, e_pot, rate


@njit(cache=True)
def begin_rows(hist, coef) -> float:
    """`begin_stages` of one history array; returns its springs' committed energy [J]."""
    e = 0.0
    for k in range(hist.shape[0]):
        if not keeps_history(coef[k]):
            continue
        e += tangential_energy(coef[k], hist[k, HIST_A], hist[k, HIST_XI], hist[k, HIST_XI + 1], hist[k, HIST_XI + 2])
        for col in range(3):
            hist[k, HIST_XI_END + col] = 0.0
            hist[k, HIST_F_END + col] = 0.0
        hist[k, HIST_A_END] = -1.0
    return e


@njit(cache=True)
def begin_stages(g, cfg) -> float:
    """Before an RK4 step's first stage (with cfg.history_stages, else nothing): every
    Mindlin contact's stage sums and increment zero, HIST_A_END = -1 (inside a step).
    Returns the springs' committed energy [J] (0 without Mindlin's law)."""
    if not cfg.history_stages:
        return 0.0
    return (
        begin_rows(g.pair_hist, g.pair_coef) + begin_rows(g.wall_hist, g.wall_coef) + begin_rows(g.pc_hist, g.pc_coef)
    )


@njit(cache=True)
def next_rows(hist, coef, weight, tau, final):
    """`next_stage` of one history array."""
    for k in range(hist.shape[0]):
        if not keeps_history(coef[k]):
            continue
        for col in range(3):
            v = hist[k, HIST_F_END + col]
            s = hist[k, HIST_XI_END + col] + weight * v
            hist[k, HIST_XI_END + col] = s
            hist[k, HIST_F_END + col] = tau * s if final else tau * v


@njit(cache=True)
def next_stage(g, cfg, weight, tau, final):
    """After an RK4 stage (with cfg.history_stages, else nothing): its slip velocity (HIST_F_END) added with `weight` (1, 2, 2, 1)
    to each Mindlin contact's sum (HIST_XI_END), and the next stage's increment tau times
    it [m] (tau = h/2, h/2, h [s]), or at the last (final) tau = h/6 times the sum."""
    if not cfg.history_stages:
        return
    next_rows(g.pair_hist, g.pair_coef, weight, tau, final)
    next_rows(g.wall_hist, g.wall_coef, weight, tau, final)
    next_rows(g.pc_hist, g.pc_coef, weight, tau, final)


@njit(cache=True)
def energy_rows(hist, coef) -> float:
    """`stage_energy` of one history array."""
    e = 0.0
    for k in range(hist.shape[0]):
        if keeps_history(coef[k]):
            x = hist[k, HIST_XI_END]
            y = hist[k, HIST_XI_END + 1]
            z = hist[k, HIST_XI_END + 2]
            e += tangential_energy(coef[k], hist[k, HIST_A_END], x, y, z)
    return e


@njit(cache=True)
def spring_rise(g, cfg, e_start) -> float:
    """The rise of the springs' energy over the step [J]: that of the trial histories at its
    end less e_start [J], what `begin_stages` returned (0 without Mindlin's law)."""
    if not cfg.history_stages:
        return 0.0
    e_end = energy_rows(g.pair_hist, g.pair_coef) + energy_rows(g.wall_hist, g.wall_coef)
    return e_end + energy_rows(g.pc_hist, g.pc_coef) - e_start

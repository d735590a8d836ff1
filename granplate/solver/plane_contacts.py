"""The plane's contact loops, one per contact kind (docs/model.md sections 2-3): granule
pairs, rigid walls and the plate's rigid layers, each adding its forces (eqs. 2-6, each
contact's normal law with its history, friction unless split off) to the granules'
derivative, and the normal forces alone of the velocity-Verlet pass. Compiled inline
(numba `inline="always"`) into `solver.granular`'s `granular_rhs` and `normal_forces`, which
thread their running sums through them in order, so the sums are bit for bit those of one
loop after the other.
"""

from __future__ import annotations

from numba import njit

from granplate.model.inputs import HIST_END, HIST_MAX, HIST_RATE
from granplate.physics.contact import (
    COEF_KS,
    COEF_MU,
    contact_arm,
    friction_magnitude,
    friction_power,
    friction_slope,
    pair_apart,
    pair_normal_rate,
    pair_overlap,
    pair_rates,
    plate_overlap,
    plate_rates,
    wall_overlap,
    wall_rates,
)
from granplate.physics.laws import normal_law_response
from granplate.physics.shock import shock_amplitude
from granplate.solver.drives import book_wall, wall_motion
from granplate.solver.state import PARTNER_PLATE


@njit(cache=True)
def slip_relaxation_rate(n, vt, mu, k_s, inv_mass_t):
    """How fast the slip of a sticking contact relaxes [1/s]: the friction slope
    (eq. 8's d f/d v_t) times the contact's tangential inverse mass; zero out of touch."""
    if n <= 0.0:
        return 0.0
    return friction_slope(n, vt, mu, k_s) * inv_mass_t


@njit(cache=True, inline="always")
def positions_rates(y, dy):
    """dy[i] = (vx, vy, omega, 0, 0, 0): the positions' rates, the forces' columns cleared
    for the contact loops to add to."""
    for i in range(y.shape[0]):
        dy[i, 0] = y[i, 3]
        dy[i, 1] = y[i, 4]
        dy[i, 2] = y[i, 5]
        dy[i, 3] = 0.0
        dy[i, 4] = 0.0
        dy[i, 5] = 0.0


@njit(cache=True, inline="always")
def shock_on_granules(t, y, g, cfg, force, load):
    """The shock's force and torque on the loaded granules at t (docs/model.md section 5.1;
    none when the line load is on the plate) added to force[:, 3] and force[:, 5] and, with
    load (ng, 6) of at least one row, written into load's; returns their power at y [W]."""
    p_shock = 0.0
    if not cfg.load_on_plate:
        amp = shock_amplitude(t, cfg)
        if amp != 0.0:
            for i in range(y.shape[0]):
                fx = amp * g.shock_force[i]
                tq = amp * g.shock_torque[i]
                if load.shape[0] > 0:
                    load[i, 3] = fx
                    load[i, 5] = tq
                force[i, 3] += fx
                force[i, 5] += tq
                p_shock += fx * y[i, 3] + tq * y[i, 5]
    return p_shock


@njit(cache=True, inline="always")
def pair_forces(y, g, cfg, dy, split, record, p_visc, p_fric, e_pot, w_plastic, rate, ovl, ovl_i, ovl_j):
    """The granule-granule contacts' forces (eqs. 2-6) added to dy[:, 3:6] (forces and
    torques, before the masses divide them): the normal law of each contact's row with its
    history, and friction unless `split` (friction_flow applies it); record: each overlap
    into HIST_END.

    The running sums come in and go out in the order of `granular_rhs`'s own (so that
    each sum adds its terms in the same order, bit for bit): viscous and friction power
    [W], stored energy [J], plastic work [J], the largest slip relaxation rate [1/s] and
    the largest overlap over the smaller radius with its granule and partner."""
    for p in range(g.pair_ij.shape[0]):  # granule-granule contacts
        i = g.pair_ij[p, 0]
        j = g.pair_ij[p, 1]
        ri = g.radius[i]
        rj = g.radius[j]
        if record:
            g.pair_hist[p, HIST_END] = 0.0
        if pair_apart(y[i, 0], y[i, 1], ri, y[j, 0], y[j, 1], rj):
            continue
        delta, nx, nz = pair_overlap(y[i, 0], y[i, 1], ri, y[j, 0], y[j, 1], rj)
        if delta <= 0.0:
            continue
        if record:
            g.pair_hist[p, HIST_END] = delta
        if delta > ovl * min(ri, rj):
            ovl = delta / min(ri, rj)
            ovl_i = i
            ovl_j = j
        c = g.pair_coef[p]
        if split:  # the normal force alone: friction_flow applies the friction
            n, pv, ep, wp = normal_law_response(
                delta,
                pair_normal_rate(y[i, 3], y[i, 4], y[j, 3], y[j, 4], nx, nz),
                c,
                g.pair_hist[p, HIST_MAX],
                g.pair_hist[p, HIST_RATE],
                cfg.clip,
            )
            w_plastic += wp
            fx = -n * nx
            fz = -n * nz
            dy[i, 3] += fx
            dy[i, 4] += fz
            dy[j, 3] -= fx
            dy[j, 4] -= fz
            p_visc += pv
            e_pot += ep
            continue
        ai = contact_arm(ri, delta, 0.5 * cfg.arm_shrink)
        aj = contact_arm(rj, delta, 0.5 * cfg.arm_shrink)
        ddot, vt = pair_rates(y[i, 3], y[i, 4], y[i, 5], y[j, 3], y[j, 4], y[j, 5], nx, nz, ai, aj)
        n, pv, ep, wp = normal_law_response(
            delta, ddot, c, g.pair_hist[p, HIST_MAX], g.pair_hist[p, HIST_RATE], cfg.clip
        )
        f = friction_magnitude(n, vt, c[COEF_MU], c[COEF_KS])
        pf = friction_power(f, vt)
        w_plastic += wp
        rate = max(
            rate,
            slip_relaxation_rate(
                n,
                vt,
                c[COEF_MU],
                c[COEF_KS],
                1.0 / g.mass[i] + 1.0 / g.mass[j] + ai * ai / g.inertia[i] + aj * aj / g.inertia[j],
            ),
        )
        fx = -n * nx + f * nz  # on i: -n nvec - f tvec, tvec = (-nz, nx); on j the opposite
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
    return p_visc, p_fric, e_pot, w_plastic, rate, ovl, ovl_i, ovl_j


@njit(cache=True, inline="always")
def wall_forces(y, g, cfg, dy, split, record, p_visc, p_fric, e_pot, w_plastic, rate, ovl, ovl_i, ovl_j):
    """The rigid walls' forces on their granules (eqs. 2-6; a driven wall moving along its
    normal, its load booked, solver.drives) added to dy[:, 3:6], as `pair_forces`.
    The running sums come in and go out in the order of `granular_rhs`'s own (so that
    each sum adds its terms in the same order, bit for bit): viscous and friction power
    [W], stored energy [J], plastic work [J], the largest slip relaxation rate [1/s] and
    the largest overlap over the smaller radius with its granule and partner."""
    for w in range(g.wall_i.shape[0]):  # rigid walls (a driven one moving along its normal at vn)
        i = g.wall_i[w]
        ri = g.radius[i]
        nx = g.wall_geo[w, 0]
        nz = g.wall_geo[w, 1]
        shift, vn, kd = wall_motion(g, w)
        delta = wall_overlap(y[i, 0], y[i, 1], ri, nx, nz, g.wall_geo[w, 2] + shift)
        if record:
            g.wall_hist[w, HIST_END] = max(delta, 0.0)
        if delta <= 0.0:
            continue
        if delta > ovl * ri:
            ovl = delta / ri
            ovl_i = i
            ovl_j = -1 - g.wall_w[w]
        c = g.wall_coef[w]
        if split:  # the normal force alone: friction_flow applies the friction
            rate_n = y[i, 3] * nx + y[i, 4] * nz - vn
            n, pv, ep, wp = normal_law_response(
                delta, rate_n, c, g.wall_hist[w, HIST_MAX], g.wall_hist[w, HIST_RATE], cfg.clip
            )
            w_plastic += wp
            book_wall(g, w, kd, n, pv / rate_n if pv != 0.0 else 0.0)
            dy[i, 3] += -n * nx
            dy[i, 4] += -n * nz
            p_visc += pv
            e_pot += ep
            continue
        ai = contact_arm(ri, delta, cfg.arm_shrink)
        ddot, vt = wall_rates(y[i, 3], y[i, 4], y[i, 5], nx, nz, ai)
        n, pv, ep, wp = normal_law_response(
            delta, ddot - vn, c, g.wall_hist[w, HIST_MAX], g.wall_hist[w, HIST_RATE], cfg.clip
        )
        book_wall(g, w, kd, n, pv / (ddot - vn) if pv != 0.0 else 0.0)
        f = friction_magnitude(n, vt, c[COEF_MU], c[COEF_KS])
        pf = friction_power(f, vt)
        w_plastic += wp
        rate = max(rate, slip_relaxation_rate(n, vt, c[COEF_MU], c[COEF_KS], 1.0 / g.mass[i] + ai * ai / g.inertia[i]))
        dy[i, 3] += -n * nx + f * nz
        dy[i, 4] += -n * nz - f * nx
        dy[i, 5] -= f * ai
        p_visc += pv
        p_fric += pf
        e_pot += ep
    return p_visc, p_fric, e_pot, w_plastic, rate, ovl, ovl_i, ovl_j


@njit(cache=True, inline="always")
def plate_contact_forces(
    y,
    up,
    vp,
    g,
    cfg,
    dy,
    fplate,
    normal,
    slip,
    hold,
    fbar,
    record,
    p_visc,
    p_fric,
    e_pot,
    w_plastic,
    rate_plate,
    ovl,
    ovl_i,
    ovl_j,
):
    """The plate contacts' forces through the rigid layers (normal (1, 0), the layer at its
    driving dofs' displacement up and velocity vp) added to dy[:, 3:6], the force on the
    plate into fplate, the normal force and slip rate into normal, slip; hold: the friction
    is fbar[k] (held over the step) instead of eq. (5). The running sums as `pair_forces`'s,
    with the largest slip relaxation rate of a plate contact (0 with hold)."""
    for k in range(g.pc_i.shape[0]):  # plate contacts through the rigid layers, n = (1, 0)
        i = g.pc_i[k]
        ri = g.radius[i]
        delta = plate_overlap(y[i, 0], ri, g.pc_x[k] + up[2 * k])
        ai = contact_arm(ri, max(delta, 0.0), cfg.arm_shrink)
        ddot, vt = plate_rates(y[i, 3], y[i, 4], y[i, 5], ai, vp[2 * k], vp[2 * k + 1])
        if record:
            g.pc_hist[k, HIST_END] = max(delta, 0.0)
        n = 0.0
        f = 0.0
        pf = 0.0
        if delta > 0.0:
            if delta > ovl * ri:
                ovl = delta / ri
                ovl_i = i
                ovl_j = PARTNER_PLATE
            c = g.pc_coef[k]
            n, pv, ep, wp = normal_law_response(
                delta, ddot, c, g.pc_hist[k, HIST_MAX], g.pc_hist[k, HIST_RATE], cfg.clip
            )
            f = friction_magnitude(n, vt, c[COEF_MU], c[COEF_KS])
            pf = friction_power(f, vt)
            w_plastic += wp
            if not hold:  # the granule side only: the plate side of this map is criterion (8)
                rate_plate = max(
                    rate_plate,
                    slip_relaxation_rate(n, vt, c[COEF_MU], c[COEF_KS], 1.0 / g.mass[i] + ai * ai / g.inertia[i]),
                )
            dy[i, 3] -= n
            p_visc += pv
            e_pot += ep
        if hold:
            f = fbar[k]
            pf = 0.0
        if f != 0.0:
            dy[i, 4] -= f
            dy[i, 5] -= f * ai
            p_fric += pf
        fplate[2 * k] = n
        fplate[2 * k + 1] = f
        normal[k] = n
        slip[k] = vt
    return p_visc, p_fric, e_pot, w_plastic, rate_plate, ovl, ovl_i, ovl_j


@njit(cache=True, inline="always")
def to_accelerations(dy, g):
    """dy[:, 3:6] from forces and torques to accelerations: / m, / m, / I."""
    for i in range(dy.shape[0]):
        dy[i, 3] /= g.mass[i]
        dy[i, 4] /= g.mass[i]
        dy[i, 5] /= g.inertia[i]


@njit(cache=True, inline="always")
def pair_normal_forces(y, g, cfg, acc, fdamp, p_visc, e_pot, w_plastic, ovl, ovl_i, ovl_j):
    """The granule pairs' normal forces (eqs. 2-4, each contact's law and history; no
    friction) added to acc[:, 3:5], their damping parts to fdamp, each overlap into
    HIST_END. The running sums come in and go out in `normal_forces`' order (bit for bit):
    viscous power [W], stored energy [J], plastic work [J], the largest overlap over the
    smaller radius with its granule and partner."""
    for p in range(g.pair_ij.shape[0]):
        i = g.pair_ij[p, 0]
        j = g.pair_ij[p, 1]
        ri = g.radius[i]
        rj = g.radius[j]
        g.pair_hist[p, HIST_END] = 0.0
        if pair_apart(y[i, 0], y[i, 1], ri, y[j, 0], y[j, 1], rj):
            continue
        delta, nx, nz = pair_overlap(y[i, 0], y[i, 1], ri, y[j, 0], y[j, 1], rj)
        if delta <= 0.0:
            continue
        g.pair_hist[p, HIST_END] = delta
        if delta > ovl * min(ri, rj):
            ovl = delta / min(ri, rj)
            ovl_i = i
            ovl_j = j
        ddot = pair_normal_rate(y[i, 3], y[i, 4], y[j, 3], y[j, 4], nx, nz)
        n, pv, ep, wp = normal_law_response(
            delta, ddot, g.pair_coef[p], g.pair_hist[p, HIST_MAX], g.pair_hist[p, HIST_RATE], cfg.clip
        )
        w_plastic += wp
        p_visc += pv
        e_pot += ep
        fx = -n * nx
        fz = -n * nz
        acc[i, 3] += fx
        acc[i, 4] += fz
        acc[j, 3] -= fx
        acc[j, 4] -= fz
        if pv != 0.0:  # the damping part of |N|, pv / ddot (eq. 3; with clip, what is left of it)
            d = pv / ddot
            fdamp[i, 3] -= d * nx
            fdamp[i, 4] -= d * nz
            fdamp[j, 3] += d * nx
            fdamp[j, 4] += d * nz
    return p_visc, e_pot, w_plastic, ovl, ovl_i, ovl_j


@njit(cache=True, inline="always")
def wall_normal_forces(y, g, cfg, acc, fdamp, p_visc, e_pot, w_plastic, ovl, ovl_i, ovl_j):
    """The rigid walls' normal forces on their granules (a driven wall moving along its
    normal, its load booked) added to acc, fdamp as `pair_normal_forces`, with its sums."""
    for w in range(g.wall_i.shape[0]):
        i = g.wall_i[w]
        ri = g.radius[i]
        nx = g.wall_geo[w, 0]
        nz = g.wall_geo[w, 1]
        shift, vn, kd = wall_motion(g, w)
        delta = wall_overlap(y[i, 0], y[i, 1], ri, nx, nz, g.wall_geo[w, 2] + shift)
        g.wall_hist[w, HIST_END] = max(delta, 0.0)
        if delta <= 0.0:
            continue
        if delta > ovl * ri:
            ovl = delta / ri
            ovl_i = i
            ovl_j = -1 - g.wall_w[w]
        ddot = y[i, 3] * nx + y[i, 4] * nz - vn
        n, pv, ep, wp = normal_law_response(
            delta, ddot, g.wall_coef[w], g.wall_hist[w, HIST_MAX], g.wall_hist[w, HIST_RATE], cfg.clip
        )
        w_plastic += wp
        p_visc += pv
        e_pot += ep
        acc[i, 3] -= n * nx
        acc[i, 4] -= n * nz
        d = 0.0
        if pv != 0.0:
            d = pv / ddot
            fdamp[i, 3] -= d * nx
            fdamp[i, 4] -= d * nz
        book_wall(g, w, kd, n, d)
    return p_visc, e_pot, w_plastic, ovl, ovl_i, ovl_j

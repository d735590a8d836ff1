"""The granular medium in the plane: the time derivative of every granule's state
(x, y, theta, vx, vy, omega) with the contact forces of eqs. (2)-(6), the split-off
friction, the kinetic energies (docs/model.md section 6); solver.rk4 steps it (through
solver.dimension, which picks this module or solver.granular3d).

Friction at granule-granule and granule-wall contacts relaxes the slip at a rate that
grows with |N| (`slip_relaxation_rate`); RK4 is stable only while the step times that
rate stays below ~2.8. With cfg.split_friction (solver.granular_friction = "split") that
friction is split off every step (Strang): half a step of friction alone, solved exactly
contact by contact (`friction_flow`), RK4 of every other force, the other half of
friction in the reverse contact order; stable for any step. Without it, RK4 integrates
every force and the step control keeps h times that rate within rk4.RK4_FRICTION_LIMIT.
"""

from __future__ import annotations

from typing import NamedTuple

from granplate.jit import njit

from granplate.model.inputs import (
    HIST_A,
    HIST_A_END,
    HIST_END,
    HIST_MAX,
    HIST_RATE,
    HIST_TIME,
    HIST_XI,
    HIST_XI_END,
    N_MINDLIN,
)
from granplate.physics.contact import (
    COEF_MU,
    contact_arm,
    friction_power,
    pair_apart,
    pair_normal_rate,
    pair_overlap,
    pair_rates,
    plate_overlap,
    plate_rates,
    wall_overlap,
    wall_rates,
)
from granplate.physics.laws import (
    keeps_history,
    normal_law_force,
    normal_law_rate,
    normal_law_response,
    tangential_friction,
    tangential_relaxed_slip,
    tangential_slopes,
)
from granplate.physics.shock import shock_amplitude
from granplate.solver.clearing import clear_overlap, clear_rows
from granplate.solver.drives import begin_pass, book_wall, finish_pass, wall_motion
from granplate.solver.mindlin_rk4 import plane_stages, plate_stages
from granplate.solver.state import PARTNER_PLATE


class ForceSums(NamedTuple):
    """What one evaluation of the granular forces (`granular_rhs`) gives besides the
    derivative: sums over the contacts and the largest values the step control and the
    contact watch read (numba compiles it as a named tuple; read it by name)."""

    p_shock: float  # power of the shock on the granules [W]
    p_visc: float  # viscous power of the normal damping [W]
    p_fric: float  # friction power [W] (without the split-off friction)
    e_pot: float  # elastic energy stored in the contacts [J] (eq. 9)
    rate: float  # largest slip relaxation rate of a granule-granule or granule-wall contact [1/s]
    ovl: float  # largest overlap over the smaller radius [-]
    ovl_i: int  # its granule (-1 with no overlap)
    ovl_j: int  # its partner: granule j, wall -1 - w or PARTNER_PLATE (-1 with no overlap)
    rate_plate: float  # largest slip relaxation rate of a plate contact [1/s] (0 with hold)
    w_plastic: float  # plastic work done past the contacts' largest overlaps so far [J] (docs/model.md eq. P10)
    p_drive: float  # power of the drives [W] (solver.drives.finish_pass; 0 in the Verlet force pass)
    p_grav: float  # power of gravity [W] (likewise)


@njit(cache=True)
def slip_relaxation_rate(n, vt, c, inv_mass_t):
    """How fast the slip of a sticking contact relaxes [1/s]: its rate law's slope (eq. 8's
    d f/d v_t; coefficient row c) times the contact's tangential inverse mass; zero out of touch."""
    if n <= 0.0:
        return 0.0
    return tangential_slopes(n, vt, c)[1] * inv_mass_t


@njit(cache=True)
def granular_rhs(t, y, up, vp, g, cfg, dy, fplate, normal, slip, hold, fbar, split=False, record=False):
    """Time derivative of the granular state and the plate-contact forces.

    y: (ng, 6) state; up, vp: driving-DOF displacement and velocity at t; writes dy,
    fplate (nd,) = force ON the plate [N, N] per contact, normal and slip at each plate
    contact. hold: the plate-contact friction is fbar[k] (held over the step, its work
    booked by the scheme) instead of eq. (5); split: no friction at granule-granule and
    granule-wall contacts (`friction_flow` applies it; their slip relaxation rate is then
    not computed, and ForceSums.rate is 0); record: each contact's overlap (0 out of
    touch) goes into the HIST_END column of its history (g.pair_hist, wall_hist, pc_hist),
    for `commit_history` once the step is accepted. Each contact's normal law is chosen by
    its coefficient row (physics.laws) with its largest overlap so far. Returns the ForceSums (powers, stored energy,
    the largest overlap and its contact, the largest slip relaxation rates); RK4 needs h
    times a rate below ~2.8. One function
    (not one per contact kind): calls that pass the model tuples cost more per step
    than the loops themselves when the medium is small.
    """
    ng = y.shape[0]
    for i in range(ng):
        dy[i, 0] = y[i, 3]
        dy[i, 1] = y[i, 4]
        dy[i, 2] = y[i, 5]
        dy[i, 3] = 0.0
        dy[i, 4] = 0.0
        dy[i, 5] = 0.0
    begin_pass(t, g)
    p_shock = 0.0
    p_visc = 0.0
    p_fric = 0.0
    e_pot = 0.0
    rate = 0.0
    rate_plate = 0.0
    ovl = 0.0  # the largest overlap / smaller radius, at granule ovl_i with ovl_j
    ovl_i = -1
    ovl_j = -1
    w_plastic = 0.0
    if not cfg.load_on_plate:  # the shock on the loaded granules
        amp = shock_amplitude(t, cfg)
        if amp != 0.0:
            for i in range(ng):
                fx = amp * g.shock_force[i]
                tq = amp * g.shock_torque[i]
                dy[i, 3] += fx
                dy[i, 5] += tq
                p_shock += fx * y[i, 3] + tq * y[i, 5]
    for p in range(g.pair_ij.shape[0]):  # granule-granule contacts
        i = g.pair_ij[p, 0]
        j = g.pair_ij[p, 1]
        ri = g.radius[i]
        rj = g.radius[j]
        if record:
            clear_overlap(g.pair_hist, p)
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
        f = tangential_friction(n, vt, c)
        pf = friction_power(f, vt)
        w_plastic += wp
        rate = max(
            rate,
            slip_relaxation_rate(
                n,
                vt,
                c,
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
        f = tangential_friction(n, vt, c)
        pf = friction_power(f, vt)
        w_plastic += wp
        rate = max(rate, slip_relaxation_rate(n, vt, c, 1.0 / g.mass[i] + ai * ai / g.inertia[i]))
        dy[i, 3] += -n * nx + f * nz
        dy[i, 4] += -n * nz - f * nx
        dy[i, 5] -= f * ai
        p_visc += pv
        p_fric += pf
        e_pot += ep
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
            f = tangential_friction(n, vt, c)
            pf = friction_power(f, vt)
            w_plastic += wp
            if not hold:  # the granule side only: the plate side of this map is criterion (8)
                rate_plate = max(
                    rate_plate,
                    slip_relaxation_rate(n, vt, c, 1.0 / g.mass[i] + ai * ai / g.inertia[i]),
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
    if cfg.history_stages:  # Mindlin's law in RK4's stages (solver.mindlin_rk4)
        p_fric, e_pot, rate = plane_stages(y, dy, g, cfg, record, p_fric, e_pot, rate)
        p_fric, e_pot, rate = plate_stages(y, up, g, cfg, record, dy, fplate, normal, slip, p_fric, e_pot, rate)
    for i in range(ng):
        dy[i, 3] /= g.mass[i]
        dy[i, 4] /= g.mass[i]
        dy[i, 5] /= g.inertia[i]
    p_drive, p_grav = finish_pass(y, dy, g)
    return ForceSums(p_shock, p_visc, p_fric, e_pot, rate, ovl, ovl_i, ovl_j, rate_plate, w_plastic, p_drive, p_grav)


@njit(cache=True)
def friction_impulse(vt, n, c, inv_mass_t, dt):
    """Friction alone at one contact of coefficient row c over dt [s] (|N| = n held): the
    slip rate vt [m/s] relaxes exactly by its rate law's flow (eq. 5's for the tanh law,
    `laws.tangential_relaxed_slip`) to v1. Returns (the impulse P = (vt - v1) / m_t^-1
    [N s], along -t on the first body, and the energy it dissipates, the kinetic energy it
    removes, P (vt + v1) / 2 >= 0 [J])."""
    v1 = tangential_relaxed_slip(vt, n, c, inv_mass_t, dt)
    imp = (vt - v1) / inv_mass_t
    return imp, 0.5 * imp * (vt + v1)


@njit(cache=True)
def friction_flow(y, dt, g, cfg, forward):
    """Friction alone at every granule-granule and granule-wall contact over dt [s], one
    contact after the other (`friction_impulse`, |N| at the current state; pairs then
    walls, or with forward False the reverse order, so that two half steps in opposite
    orders make a symmetric split). Changes the velocities and spins in y, never the
    positions. Returns the energy dissipated [J] (>= 0, booked exactly as the kinetic
    energy each contact removes). One function, not one call per contact (a call that
    passes the model tuples costs more than a contact)."""
    n_p = g.pair_ij.shape[0]
    n_w = g.wall_i.shape[0]
    work = 0.0
    for k in range(n_p + n_w):
        q = k if forward else n_p + n_w - 1 - k
        if q < n_p:  # pair q: -P t on i, +P t on j, t = (-nz, nx); torques -P a
            i = g.pair_ij[q, 0]
            j = g.pair_ij[q, 1]
            ri = g.radius[i]
            rj = g.radius[j]
            if pair_apart(y[i, 0], y[i, 1], ri, y[j, 0], y[j, 1], rj):
                continue
            delta, nx, nz = pair_overlap(y[i, 0], y[i, 1], ri, y[j, 0], y[j, 1], rj)
            c = g.pair_coef[q]
            if delta <= 0.0 or c[COEF_MU] == 0.0:
                continue
            ai = contact_arm(ri, delta, 0.5 * cfg.arm_shrink)
            aj = contact_arm(rj, delta, 0.5 * cfg.arm_shrink)
            ddot, vt = pair_rates(y[i, 3], y[i, 4], y[i, 5], y[j, 3], y[j, 4], y[j, 5], nx, nz, ai, aj)
            n = normal_law_force(delta, ddot, c, g.pair_hist[q, HIST_MAX], g.pair_hist[q, HIST_RATE], cfg.clip)
            inv_mi = 1.0 / g.mass[i]
            inv_mj = 1.0 / g.mass[j]
            inv_ii = ai / g.inertia[i]  # the spin change per unit impulse
            inv_ij = aj / g.inertia[j]
            imp, dw = friction_impulse(vt, n, c, inv_mi + inv_mj + ai * inv_ii + aj * inv_ij, dt)
            y[i, 3] += imp * nz * inv_mi
            y[i, 4] -= imp * nx * inv_mi
            y[i, 5] -= imp * inv_ii
            y[j, 3] -= imp * nz * inv_mj
            y[j, 4] += imp * nx * inv_mj
            y[j, 5] -= imp * inv_ij
            work += dw
        else:  # wall contact w (a driven wall where the last force pass put it; it moves along its normal)
            w = q - n_p
            i = g.wall_i[w]
            ri = g.radius[i]
            nx = g.wall_geo[w, 0]
            nz = g.wall_geo[w, 1]
            shift, vn, _ = wall_motion(g, w)
            delta = wall_overlap(y[i, 0], y[i, 1], ri, nx, nz, g.wall_geo[w, 2] + shift)
            c = g.wall_coef[w]
            if delta <= 0.0 or c[COEF_MU] == 0.0:
                continue
            ai = contact_arm(ri, delta, cfg.arm_shrink)
            ddot, vt = wall_rates(y[i, 3], y[i, 4], y[i, 5], nx, nz, ai)
            n = normal_law_force(delta, ddot - vn, c, g.wall_hist[w, HIST_MAX], g.wall_hist[w, HIST_RATE], cfg.clip)
            inv_m = 1.0 / g.mass[i]
            inv_i = ai / g.inertia[i]
            imp, dw = friction_impulse(vt, n, c, inv_m + ai * inv_i, dt)
            y[i, 3] += imp * nz * inv_m
            y[i, 4] -= imp * nx * inv_m
            y[i, 5] -= imp * inv_i
            work += dw
    return work


@njit(cache=True)
def commit_history(t, hist, coef):
    """Take the accepted step's end overlaps (column HIST_END) into the contacts' largest
    overlaps (HIST_MAX, reached at time t [s]: HIST_TIME) of one history array, and update
    the rate factor (HIST_RATE) of a contact whose largest overlap grows as its normal law
    says (coefficient rows `coef`; `laws.normal_law_rate`: the law "johnson" fixes its
    yield strength in the step where its largest overlap first passes yield)."""
    commit_rows(t, hist, coef, 0, hist.shape[0])


@njit(cache=True, inline="always")
def commit_overlap(t, hist, k, d, c):
    """Contact k's overlap d [m] at the accepted step's end t [s] into its largest
    overlap (HIST_MAX, reached at HIST_TIME) where it exceeds it, its rate factor
    (HIST_RATE) updated as its law says (coefficient row c; `laws.normal_law_rate`)."""
    if d > hist[k, HIST_MAX]:
        hist[k, HIST_RATE] = normal_law_rate(d, hist[k, HIST_MAX], t, hist[k, HIST_TIME], hist[k, HIST_RATE], c)
        hist[k, HIST_MAX] = d
        hist[k, HIST_TIME] = t


@njit(cache=True)
def commit_rows(t, hist, coef, lo, hi):
    """`commit_history` of contacts lo..hi-1 (written out per row: a compiled call per row
    costs 4.6x this loop, measured on 56,754 rows)."""
    # rows that keep a trial tangential history apart (model.inputs.history_columns: N_HIST; a
    # row of N_HIST_STEP, velocity Verlet's, was moved on in place by the force pass)
    tangential = hist.shape[1] > HIST_A_END
    for k in range(lo, hi):
        # a tangential law's history (Mindlin's, docs/model.md section 3.16); a contact out of
        # touch with none, before and after (HIST_A and HIST_A_END zero: its rows are zeros), keeps its zeros
        if tangential and (hist[k, HIST_A_END] != 0.0 or hist[k, HIST_A] != 0.0) and keeps_history(coef[k]):
            for col in range(N_MINDLIN):
                hist[k, HIST_XI + col] = hist[k, HIST_XI_END + col]
        commit_overlap(t, hist, k, hist[k, HIST_END], coef[k])


@njit(entry=True, cache=True)
def commit_histories(t, g):
    """`commit_history` of every contact kind of g (pairs, walls, plate contacts)."""
    commit_history(t, g.pair_hist, g.pair_coef)
    commit_history(t, g.wall_hist, g.wall_coef)
    commit_history(t, g.pc_hist, g.pc_coef)


@njit(cache=True)
def force_error(k1, k0, kend, ratio, mass, inertia, radius, sc, err):
    """The implicit scheme's error terms of the granules (solver.schemes.implicit.step_error):
    the net forces m a_x, m a_y and I alpha / R at the end of the step (kend) against their
    linear extrapolation over the last two steps (k1, k0, ratio); returns (the largest
    force seen, sc, and the largest distance, err) [N]."""
    for i in range(kend.shape[0]):
        for c in range(3):
            m = mass[i] if c < 2 else inertia[i] / radius[i]
            sc = max(sc, m * abs(kend[i, 3 + c]))
            pred = k1[i, 3 + c] + ratio * (k1[i, 3 + c] - k0[i, 3 + c])
            err = max(err, m * abs(kend[i, 3 + c] - pred))
    return sc, err


@njit(cache=True)
def kinetic_energies(y, mass, inertia, kx=0.0, ky=0.0, kr=0.0):
    """Horizontal, vertical and rotational kinetic energy of the granules [J] (eq. 10),
    added in granule order to kx, ky, kr (those of granules before these: a range's sums
    carried on). (Arrays, not the model tuple: this runs every step.)"""
    for i in range(y.shape[0]):
        kx += 0.5 * mass[i] * y[i, 3] * y[i, 3]
        ky += 0.5 * mass[i] * y[i, 4] * y[i, 4]
        kr += 0.5 * inertia[i] * y[i, 5] * y[i, 5]
    return kx, ky, kr


@njit(cache=True)
def normal_forces(t, y, g, cfg, acc, fdamp, fload, commit_t, forces=True, damp=True, loads=True, divide=True):
    """The velocity-Verlet force pass (solver.schemes.verlet) in the plane: the shock on
    the loaded granules and the normal force (eqs. 2-4, physics.laws with each contact's
    history) of every listed pair and wall contact at state y, whose velocities are the
    ones the damping reads; no friction (the scheme applies it by `friction_flow`). Writes
    the accelerations into acc[:, 3:6] and, apart, each granule's damping force and shock
    load (fdamp, fload [:, 3:6]: N, N, N m), from which the scheme books the work of each
    kick; each contact's overlap into its history's HIST_END (0 out of touch), a pair's
    committed at commit_t [s] (`commit_overlap`; the trial of a scheme whose every step is
    accepted; commit_t < 0: none, a pass at t_n). The rows of acc, fdamp and fload are
    cleared first where `forces`, `damp`, `loads` (solver.clearing.clear_rows); without `divide`, acc
    keeps the forces and torque (solver.kicks.divide_kick makes them accelerations). No plate
    contacts (the scheme runs without a plate). Returns the ForceSums: shock and viscous
    power at y [W], stored energy [J], the largest overlap, the plastic work past the
    largest overlaps [J]; no friction rates."""
    ng = y.shape[0]
    clear_rows(acc, fdamp, fload, 0, ng, forces, damp, loads)
    begin_pass(t, g)
    p_shock = 0.0
    p_visc = 0.0
    e_pot = 0.0
    ovl = 0.0
    ovl_i = -1
    ovl_j = -1
    w_plastic = 0.0
    if not cfg.load_on_plate:
        amp = shock_amplitude(t, cfg)
        if amp != 0.0:
            for i in range(ng):
                fx = amp * g.shock_force[i]
                tq = amp * g.shock_torque[i]
                fload[i, 3] = fx
                fload[i, 5] = tq
                acc[i, 3] += fx
                acc[i, 5] += tq
                p_shock += fx * y[i, 3] + tq * y[i, 5]
    for p in range(g.pair_ij.shape[0]):
        i = g.pair_ij[p, 0]
        j = g.pair_ij[p, 1]
        ri = g.radius[i]
        rj = g.radius[j]
        clear_overlap(g.pair_hist, p)
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
        if commit_t >= 0.0:
            commit_overlap(commit_t, g.pair_hist, p, delta, g.pair_coef[p])
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
    if divide:
        for i in range(ng):
            acc[i, 3] /= g.mass[i]
            acc[i, 4] /= g.mass[i]
            acc[i, 5] /= g.inertia[i]
    return ForceSums(p_shock, p_visc, 0.0, e_pot, 0.0, ovl, ovl_i, ovl_j, 0.0, w_plastic, 0.0, 0.0)


@njit(cache=True)
def sensor_loads(y, g, cfg, load):
    """Every granule's sensor reading at state y [N] into load (ng,): half the sum of the
    normal forces N (eqs. 2-4, compression positive, with their damping at the state's
    velocities and each contact's history) of its listed pair and wall contacts
    (docs/model.md section 3.15; the plate contacts' the caller adds). Reads, never
    writes, the contacts' histories and the walls' loads: run at the sample times alone."""
    for i in range(load.shape[0]):
        load[i] = 0.0
    for p in range(g.pair_ij.shape[0]):
        i = g.pair_ij[p, 0]
        j = g.pair_ij[p, 1]
        ri = g.radius[i]
        rj = g.radius[j]
        if pair_apart(y[i, 0], y[i, 1], ri, y[j, 0], y[j, 1], rj):
            continue
        delta, nx, nz = pair_overlap(y[i, 0], y[i, 1], ri, y[j, 0], y[j, 1], rj)
        if delta <= 0.0:
            continue
        ddot = pair_normal_rate(y[i, 3], y[i, 4], y[j, 3], y[j, 4], nx, nz)
        n = normal_law_force(delta, ddot, g.pair_coef[p], g.pair_hist[p, HIST_MAX], g.pair_hist[p, HIST_RATE], cfg.clip)
        load[i] += 0.5 * n
        load[j] += 0.5 * n
    for w in range(g.wall_i.shape[0]):
        i = g.wall_i[w]
        nx = g.wall_geo[w, 0]
        nz = g.wall_geo[w, 1]
        shift, vn, _ = wall_motion(g, w)
        delta = wall_overlap(y[i, 0], y[i, 1], g.radius[i], nx, nz, g.wall_geo[w, 2] + shift)
        if delta <= 0.0:
            continue
        ddot = y[i, 3] * nx + y[i, 4] * nz - vn
        n = normal_law_force(delta, ddot, g.wall_coef[w], g.wall_hist[w, HIST_MAX], g.wall_hist[w, HIST_RATE], cfg.clip)
        load[i] += 0.5 * n

"""Mindlin's tangential law in the velocity-Verlet force pass in space (docs/model.md
section 3.16): each contact's geometry and normal force, computed once by the normal pass
(solver.granular3d), serve its tangential step too (physics.mindlin through
solver.granular3d's per-contact step, `mindlin_contact`). The pairs' loop takes a range of
the pair list and writes its forces into given arrays and columns, so the serial pass
(`normal_mindlin_forces`) and the threaded one (solver.blocks, one block's buffer each) are
the same code.
"""

from __future__ import annotations

from numba import njit

from granplate.model.inputs import HIST_A, HIST_A_END, HIST_MAX, HIST_RATE
from granplate.physics.contact import COEF_TLAW, contact_arm
from granplate.physics.laws import normal_law_force
from granplate.physics.mindlin import contact_radius
from granplate.physics.space import arm_torque_3d, normal_rate_3d, wall_overlap_3d
from granplate.setup.law_registry import MINDLIN
from granplate.solver.drives import begin_pass, wall_motion
from granplate.solver.granular import ForceSums
from granplate.solver.granular3d import (
    VX,
    WX,
    X,
    Y,
    Z,
    couple_work,
    mindlin_contact,
    mindlin_old_force,
    mindlin_parted,
    pair_normal_3d,
    pair_slip,
    push_pair,
    push_tangential,
    shock_loads,
    wall_forces,
    wall_slip,
)


@njit(cache=True, inline="always")  # per contact: inlined, g not passed by value
def pair_mindlin_3d(p, i, j, delta, nx, ny, nz, n_abs, yv, h, g, cfg):
    """Mindlin's law at listed pair p in touch (granules i, j; its overlap delta [m], unit
    normal n from i to j and |N| = n_abs [N] from the force pass), the slip from yv's
    velocities over h [s]: returns (its force F_t (3) on i [N], the arms of its torques
    on i and j [m], stored energy [J], energy lost [J])."""
    ri = g.radius[i]
    rj = g.radius[j]
    half_shrink = 0.5 * cfg.arm_shrink
    ai = contact_arm(ri, delta, half_shrink)
    aj = contact_arm(rj, delta, half_shrink)
    _, vsx, vsy, vsz = pair_slip(yv, i, j, nx, ny, nz, ai, aj)
    a = contact_radius(ri * rj / (ri + rj), delta)
    hist = g.pair_hist
    c = g.pair_coef[p]
    f0x, f0y, f0z = mindlin_old_force(hist, p, c)
    fx, fy, fz, e, d = mindlin_contact(hist, p, c, a, delta, nx, ny, nz, vsx, vsy, vsz, h, n_abs)
    ti = ai
    tj = aj
    if cfg.lammps_arms:  # LAMMPS's torque arms: their couples' extra work over h is lost from D
        ti = ri - 0.5 * delta
        tj = rj - 0.5 * delta
        d -= couple_work(yv, i, ti - ai, nx, ny, nz, f0x + fx, f0y + fy, f0z + fz, 0.5 * h)
        d -= couple_work(yv, j, tj - aj, nx, ny, nz, f0x + fx, f0y + fy, f0z + fz, 0.5 * h)
    return fx, fy, fz, ti, tj, e, d


@njit(cache=True, inline="always")  # per contact: inlined, g not passed by value
def push_couple(out, i, col, arm, nx, ny, nz, fx, fy, fz):
    """The torque arm n x F [N m] (F on the first body [N]) into out[i, col:col + 3]."""
    tx, ty, tz = arm_torque_3d(arm, nx, ny, nz, fx, fy, fz)
    out[i, col] += tx
    out[i, col + 1] += ty
    out[i, col + 2] += tz


@njit(cache=True)
def pair_forces_mindlin(yv, yn, h, g, cfg, lo, hi, out, out_d, c_f, c_d, c_t):
    """Listed pairs lo..hi-1 of the force pass with Mindlin's law: each pair's normal force
    at state yn (solver.granular3d.pair_normal_3d; its overlap into HIST_END) and, where its
    coefficient row names Mindlin's law (COEF_TLAW), Mindlin's force from the same overlap and |N|
    (`pair_mindlin_3d`), as forces on the granules into out[:, c_f:c_f + 3], the torques into
    out[:, c_t:c_t + 3], the normal forces' damping parts into out_d[:, c_d:c_d + 3]; a parted contact's history
    ended (`mindlin_parted`). Returns (viscous power [W], stored energy [J], plastic work
    [J], the largest overlap / smaller radius, its pair (i, j), the springs' energy [J],
    their losses [J])."""
    p_visc = 0.0
    e_pot = 0.0
    w_plastic = 0.0
    e_t = 0.0
    lost = 0.0
    ovl = 0.0
    ovl_i = -1
    ovl_j = -1
    hist = g.pair_hist
    for p in range(lo, hi):
        delta, nx, ny, nz, n, pv, ep, wp, d = pair_normal_3d(p, yn, g, cfg.clip)
        kt = g.pair_coef[p, COEF_TLAW] == MINDLIN
        if delta <= 0.0:
            if kt and (hist[p, HIST_A] != 0.0 or hist[p, HIST_A_END] != 0.0):
                lost += mindlin_parted(hist, p, g.pair_coef[p])
            continue
        i = g.pair_ij[p, 0]
        j = g.pair_ij[p, 1]
        r_min = min(g.radius[i], g.radius[j])
        if delta > ovl * r_min:
            ovl = delta / r_min
            ovl_i = i
            ovl_j = j
        w_plastic += wp
        p_visc += pv
        e_pot += ep
        push_pair(out, i, j, c_f, n, nx, ny, nz)
        if pv != 0.0:
            push_pair(out_d, i, j, c_d, d, nx, ny, nz)
        if kt:
            fx, fy, fz, ti, tj, e, dl = pair_mindlin_3d(p, i, j, delta, nx, ny, nz, n, yv, h, g, cfg)
            e_t += e
            lost += dl
            out[i, c_f] += fx
            out[i, c_f + 1] += fy
            out[i, c_f + 2] += fz
            out[j, c_f] -= fx
            out[j, c_f + 1] -= fy
            out[j, c_f + 2] -= fz
            push_couple(out, i, c_t, ti, nx, ny, nz, fx, fy, fz)
            push_couple(out, j, c_t, tj, nx, ny, nz, fx, fy, fz)
    return p_visc, e_pot, w_plastic, ovl, ovl_i, ovl_j, e_t, lost


@njit(cache=True)
def wall_mindlin(yv, yn, h, g, cfg, acc):
    """Mindlin's law at the wall contacts whose coefficient row names Mindlin's law (COEF_TLAW), after the
    normal pass (a wall's few contacts: their geometry and |N| again): the slip from yv's
    velocities over h [s], |N| from yn's; the forces and torques added to the
    accelerations acc. Returns (the springs' energy [J], their losses [J])."""
    e_t = 0.0
    lost = 0.0
    for w in range(g.wall_i.shape[0]):
        c = g.wall_coef[w]
        if c[COEF_TLAW] != MINDLIN:
            continue
        i = g.wall_i[w]
        ri = g.radius[i]
        nx = g.wall_geo[w, 0]
        ny = g.wall_geo[w, 1]
        nz = g.wall_geo[w, 2]
        shift, vn, _ = wall_motion(g, w)
        delta = wall_overlap_3d(yn[i, X], yn[i, Y], yn[i, Z], ri, nx, ny, nz, g.wall_geo[w, 3] + shift)
        if delta <= 0.0:
            lost += mindlin_parted(g.wall_hist, w, c)
            continue
        arm = contact_arm(ri, delta, cfg.arm_shrink)
        _, vsx, vsy, vsz = wall_slip(yv, i, nx, ny, nz, arm)
        n_abs = wall_normal_force(yn, i, w, delta, nx, ny, nz, vn, g, cfg)
        a = contact_radius(ri, delta)
        fx, fy, fz, e, d = mindlin_contact(g.wall_hist, w, c, a, delta, nx, ny, nz, vsx, vsy, vsz, h, n_abs)
        e_t += e
        lost += d
        push_tangential(acc, g, i, arm, nx, ny, nz, fx, fy, fz, 1.0)
    return e_t, lost


@njit(cache=True, inline="always")  # per contact: inlined, g not passed by value
def wall_normal_force(yn, i, w, delta, nx, ny, nz, vn, g, cfg) -> float:
    """|N| [N] of wall contact w (granule i, overlap delta [m], outward normal n, the wall's
    normal velocity vn [m/s]) at state yn, as the normal pass has it."""
    ddot = normal_rate_3d(yn[i, VX], yn[i, VX + 1], yn[i, VX + 2], nx, ny, nz) - vn
    return normal_law_force(delta, ddot, g.wall_coef[w], g.wall_hist[w, HIST_MAX], g.wall_hist[w, HIST_RATE], cfg.clip)


@njit(cache=True)
def normal_mindlin_forces(t, yv, yn, h, g, cfg, acc, fdamp, fload):
    """solver.granular3d.normal_forces with Mindlin's tangential law in it (docs/model.md
    section 3.16): the shock, every listed pair and wall contact's normal force at state yn
    (its velocities the damping's) and, at the contacts whose coefficient row names Mindlin's
    law (COEF_TLAW), the tangential spring's force from the same overlap and |N|, its history moved on by
    the slip at yv's velocities over h [s] (the half step's; yv's positions are yn's; h = 0:
    the force of the committed history), the trial histories into HIST_XI_END, HIST_A_END,
    HIST_F_END. Returns (the ForceSums, the springs' stored energy [J], the energy they
    lost over the step [J])."""
    for i in range(yn.shape[0]):
        for c in range(3, 9):
            acc[i, c] = 0.0
            fdamp[i, c] = 0.0
            fload[i, c] = 0.0
    begin_pass(t, g)
    p_shock = 0.0
    if not cfg.load_on_plate:
        p_shock = shock_loads(t, yn, g, cfg, acc, fload)
    p_visc, e_pot, w_plastic, ovl, ovl_i, ovl_j, e_t, lost = pair_forces_mindlin(
        yv, yn, h, g, cfg, 0, g.pair_ij.shape[0], acc, fdamp, VX, VX, WX
    )
    p_visc, e_pot, w_plastic, ovl, ovl_i, ovl_j = wall_forces(
        yn, g, cfg, acc, fdamp, p_visc, e_pot, w_plastic, ovl, ovl_i, ovl_j
    )
    for i in range(yn.shape[0]):
        for c in range(3):
            acc[i, VX + c] /= g.mass[i]
            acc[i, WX + c] /= g.inertia[i]
    e_w, lost_w = wall_mindlin(yv, yn, h, g, cfg, acc)
    sums = ForceSums(p_shock, p_visc, 0.0, e_pot, 0.0, ovl, ovl_i, ovl_j, 0.0, w_plastic, 0.0, 0.0)
    return sums, e_t + e_w, lost + lost_w

"""Mindlin's tangential law in the plane (docs/model.md section 3.16): the law of space
(physics.mindlin through solver.mindlin_history's per-contact step, `mindlin_contact`) on the
plane's contacts, whose tangent is the normal turned by 90 degrees, t = (-n_y, n_x). The
slip velocity v_t t (eq. 6, physics.contact.pair_rates and wall_rates) enters as a vector
of space with no z component, so the history xi, the force and the frame update of eqs.
(M2)-(M5) are the same code with z = 0 (xi stays along t: its third component stays
zero); the torque of a force F at the arm a is a (n x F)_z = a F.t, on both granules.

The law runs inside the velocity-Verlet force pass (`normal_mindlin_forces`): each contact's
geometry and normal force, computed once, serve its normal force and its tangential step.
"""

from __future__ import annotations

from granplate.jit import njit

from granplate.model.inputs import HIST_END, HIST_MAX, HIST_RATE
from granplate.physics.contact import (
    contact_arm,
    pair_apart,
    pair_normal_rate,
    pair_overlap,
    pair_rates,
    wall_overlap,
    wall_rates,
)
from granplate.physics.laws import keeps_history, normal_law_response, tangential_scale
from granplate.physics.shock import shock_amplitude
from granplate.solver.drives import begin_pass, book_wall, wall_motion
from granplate.solver.clearing import clear_overlap, clear_rows
from granplate.solver.granular import ForceSums, commit_overlap
from granplate.solver.mindlin_history import mindlin_contact, mindlin_old_force, mindlin_parted, mindlin_touched


@njit(cache=True)
def couple_work_plane(y, i, da, nx, nz, fx, fy, dt):
    """The work [J] over dt [s] of the couple da (n x F)_z (da [m], F [N]) on granule i's
    spin at state y."""
    return dt * da * (nx * fy - nz * fx) * y[i, 5]


@njit(cache=True)
def pair_mindlin(p, i, j, ri, rj, delta, nx, nz, n_abs, yv, h, hist, c, half_shrink, lammps_arms):
    """Mindlin's law at listed pair p in touch (granules i, j of radii ri, rj [m]; its
    overlap delta [m], unit normal (nx, nz) and |N| = n_abs [N] from the force pass; history
    rows hist, its coefficient row c) of the plane, the slip from yv's velocities over h [s]:
    returns (its force (fx, fy) on i [N], the arms of its torques on i and j [m], stored
    energy [J], energy lost [J]). The arrays alone, not the model's tuple: this runs per
    contact and step."""
    ai = contact_arm(ri, delta, half_shrink)
    aj = contact_arm(rj, delta, half_shrink)
    _, vt = pair_rates(yv[i, 3], yv[i, 4], yv[i, 5], yv[j, 3], yv[j, 4], yv[j, 5], nx, nz, ai, aj)
    a = tangential_scale(c, ri * rj / (ri + rj), delta)
    f0x, f0y, _ = mindlin_old_force(hist, p, c)
    fx, fy, _, e, d = mindlin_contact(hist, p, c, a, delta, nx, nz, 0.0, -vt * nz, vt * nx, 0.0, h, n_abs)
    ti = ai
    tj = aj
    if lammps_arms:  # LAMMPS's torque arms: their couples' extra work over h is lost from D
        ti = ri - 0.5 * delta
        tj = rj - 0.5 * delta
        d -= couple_work_plane(yv, i, ti - ai, nx, nz, f0x + fx, f0y + fy, 0.5 * h)
        d -= couple_work_plane(yv, j, tj - aj, nx, nz, f0x + fx, f0y + fy, 0.5 * h)
    return fx, fy, ti, tj, e, d


@njit(cache=True)
def pair_forces_mindlin(yv, yn, h, g, cfg, acc, fdamp, commit_t):
    """The pairs' share of `normal_mindlin_forces`: every listed pair's normal force
    (physics.laws, as solver.granular.normal_forces) at state yn and, where its coefficient
    row's tangential law keeps a history (Mindlin's; laws.keeps_history), Mindlin's force (`pair_mindlin`) from the same overlap and |N|,
    added to acc[:, 3:6] as forces and torques; the damping parts into fdamp, each
    overlap into HIST_END (committed at commit_t [s] as solver.granular.normal_forces
    says), a parted contact's history ended (`mindlin_parted`). Returns
    (viscous power [W], stored energy [J], plastic work [J], the largest overlap / radius,
    its pair (i, j), the springs' energy [J], their losses [J])."""
    radius = g.radius
    pair_ij = g.pair_ij
    pair_coef = g.pair_coef
    hist = g.pair_hist
    half_shrink = 0.5 * cfg.arm_shrink
    lammps_arms = cfg.lammps_arms
    clip = cfg.clip
    p_visc = 0.0
    e_pot = 0.0
    w_plastic = 0.0
    e_t = 0.0
    lost = 0.0
    ovl = 0.0
    ovl_i = -1
    ovl_j = -1
    for p in range(pair_ij.shape[0]):
        i = pair_ij[p, 0]
        j = pair_ij[p, 1]
        ri = radius[i]
        rj = radius[j]
        c = pair_coef[p]
        clear_overlap(hist, p)
        delta = -1.0
        if not pair_apart(yn[i, 0], yn[i, 1], ri, yn[j, 0], yn[j, 1], rj):
            delta, nx, nz = pair_overlap(yn[i, 0], yn[i, 1], ri, yn[j, 0], yn[j, 1], rj)
        if delta <= 0.0:
            if keeps_history(c) and mindlin_touched(hist, p):
                lost += mindlin_parted(hist, p, c)
            continue
        hist[p, HIST_END] = delta
        if delta > ovl * min(ri, rj):
            ovl = delta / min(ri, rj)
            ovl_i = i
            ovl_j = j
        ddot = pair_normal_rate(yn[i, 3], yn[i, 4], yn[j, 3], yn[j, 4], nx, nz)
        n, pv, ep, wp = normal_law_response(delta, ddot, c, hist[p, HIST_MAX], hist[p, HIST_RATE], clip)
        if commit_t >= 0.0:
            commit_overlap(commit_t, hist, p, delta, c)
        w_plastic += wp
        p_visc += pv
        e_pot += ep
        fx = -n * nx
        fy = -n * nz
        if pv != 0.0:  # the damping part of |N|, pv / ddot (eq. 3)
            d = pv / ddot
            fdamp[i, 3] -= d * nx
            fdamp[i, 4] -= d * nz
            fdamp[j, 3] += d * nx
            fdamp[j, 4] += d * nz
        if keeps_history(c):
            tx, ty, ti, tj, e, d = pair_mindlin(
                p, i, j, ri, rj, delta, nx, nz, n, yv, h, hist, c, half_shrink, lammps_arms
            )
            e_t += e
            lost += d
            fx += tx
            fy += ty
            tq = nx * ty - nz * tx
            acc[i, 5] += ti * tq
            acc[j, 5] += tj * tq
        acc[i, 3] += fx
        acc[i, 4] += fy
        acc[j, 3] -= fx
        acc[j, 4] -= fy
    return p_visc, e_pot, w_plastic, ovl, ovl_i, ovl_j, e_t, lost


@njit(cache=True)
def wall_forces_mindlin(yv, yn, h, g, cfg, acc, fdamp):
    """The walls' share of `normal_mindlin_forces`, one contact after another (a wall's
    load and a driven wall's force are shared sums): each wall contact's normal force at
    state yn (as solver.granular.normal_forces, booked on its wall and drive) and, where
    a tangential law with history (Mindlin's), Mindlin's force from the same overlap and |N|, into acc[:, 3:6] as forces
    and torques. Returns (viscous power [W], stored energy [J], plastic work [J], the
    largest overlap / radius, its granule, its partner code, springs' energy [J], losses [J])."""
    p_visc = 0.0
    e_pot = 0.0
    w_plastic = 0.0
    e_t = 0.0
    lost = 0.0
    ovl = 0.0
    ovl_i = -1
    ovl_j = -1
    hist = g.wall_hist
    for w in range(g.wall_i.shape[0]):
        i = g.wall_i[w]
        ri = g.radius[i]
        c = g.wall_coef[w]
        nx = g.wall_geo[w, 0]
        nz = g.wall_geo[w, 1]
        shift, vn, kd = wall_motion(g, w)
        delta = wall_overlap(yn[i, 0], yn[i, 1], ri, nx, nz, g.wall_geo[w, 2] + shift)
        hist[w, HIST_END] = max(delta, 0.0)
        if delta <= 0.0:
            if keeps_history(c):
                lost += mindlin_parted(hist, w, c)
            continue
        if delta > ovl * ri:
            ovl = delta / ri
            ovl_i = i
            ovl_j = -1 - g.wall_w[w]
        ddot = yn[i, 3] * nx + yn[i, 4] * nz - vn
        n, pv, ep, wp = normal_law_response(delta, ddot, c, hist[w, HIST_MAX], hist[w, HIST_RATE], cfg.clip)
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
        if not keeps_history(c):
            continue
        arm = contact_arm(ri, delta, cfg.arm_shrink)
        _, vt = wall_rates(yv[i, 3], yv[i, 4], yv[i, 5], nx, nz, arm)
        a = tangential_scale(c, ri, delta)
        fx, fy, _, e, dl = mindlin_contact(hist, w, c, a, delta, nx, nz, 0.0, -vt * nz, vt * nx, 0.0, h, n)
        e_t += e
        lost += dl
        acc[i, 3] += fx
        acc[i, 4] += fy
        acc[i, 5] += arm * (nx * fy - nz * fx)
    return p_visc, e_pot, w_plastic, ovl, ovl_i, ovl_j, e_t, lost


@njit(cache=True)
def normal_mindlin_forces(t, yv, yn, h, g, cfg, acc, fdamp, fload, commit_t, forces=True, damp=True, loads=True):
    """The velocity-Verlet force pass of the plane (solver.granular.normal_forces) with
    Mindlin's tangential law (docs/model.md section 3.16) in it: the shock, every listed
    pair and wall contact's normal force at state yn (its velocities the damping's) and, at
    the contacts whose tangential law keeps a history (Mindlin's; laws.keeps_history), the tangential spring's force from
    the same overlap and |N|, its history moved on by the slip at yv's velocities over h
    [s] (the half step's; yv's positions are yn's; h = 0: the force of the committed
    history), the trial histories as solver.mindlin_history.trial_column says, the pairs'
    overlaps committed at commit_t [s] (< 0: none; solver.granular.normal_forces). Accelerations into
    acc[:, 3:6], damping forces and loads apart (fdamp, fload), their rows cleared first
    as there. Returns (the ForceSums, the
    springs' stored energy [J], the energy they lost over the step [J])."""
    ng = yn.shape[0]
    clear_rows(acc, fdamp, fload, 0, ng, forces, damp, loads)
    begin_pass(t, g)
    p_shock = 0.0
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
                p_shock += fx * yn[i, 3] + tq * yn[i, 5]
    p_visc, e_pot, w_plastic, ovl, ovl_i, ovl_j, e_t, lost = pair_forces_mindlin(
        yv, yn, h, g, cfg, acc, fdamp, commit_t
    )
    pv_w, ep_w, wp_w, ovl_w, i_w, j_w, et_w, lost_w = wall_forces_mindlin(yv, yn, h, g, cfg, acc, fdamp)
    if ovl_w > ovl:
        ovl, ovl_i, ovl_j = ovl_w, i_w, j_w
    for i in range(ng):
        acc[i, 3] /= g.mass[i]
        acc[i, 4] /= g.mass[i]
        acc[i, 5] /= g.inertia[i]
    sums = ForceSums(p_shock, p_visc + pv_w, 0.0, e_pot + ep_w, 0.0, ovl, ovl_i, ovl_j, 0.0, w_plastic + wp_w, 0.0, 0.0)
    return sums, e_t + et_w, lost + lost_w

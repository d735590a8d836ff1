"""Mindlin's tangential law in the plane (docs/model.md section 3.16): the law of space
(physics.mindlin through solver.granular3d's per-contact step, `mindlin_contact`) on the
plane's contacts, whose tangent is the normal turned by 90 degrees, t = (-n_y, n_x). The
slip velocity v_t t (eq. 6, physics.contact.pair_rates and wall_rates) enters as a vector
of space with no z component, so the history xi, the force and the frame update of eqs.
(M2)-(M5) are the same code with z = 0 (xi stays along t: its third component stays
zero); the torque of a force F at the arm a is a (n x F)_z = a F.t, on both granules.
"""

from __future__ import annotations

from numba import njit

from granplate.model.inputs import HIST_A, HIST_A_END, HIST_MAX, HIST_RATE
from granplate.physics.contact import (
    COEF_KT,
    contact_arm,
    pair_apart,
    pair_normal_rate,
    pair_overlap,
    pair_rates,
    wall_overlap,
    wall_rates,
)
from granplate.physics.laws import normal_law_force
from granplate.physics.mindlin import contact_radius
from granplate.solver.drives import wall_motion
from granplate.solver.granular3d import mindlin_contact, mindlin_old_force, mindlin_parted


@njit(cache=True)
def push_tangential_plane(acc, mass, inertia, i, arm, nx, nz, fx, fy, sign):
    """The tangential force sign * F (F = (fx, fy) on the first body [N]) and its torque
    arm (n x F)_z (arm [m], the same sign on both bodies) on granule i of the plane (mass
    [kg], moment of inertia [kg m^2] per granule) as accelerations into acc[:, 3:6]."""
    acc[i, 3] += sign * fx / mass[i]
    acc[i, 4] += sign * fy / mass[i]
    acc[i, 5] += arm * (nx * fy - nz * fx) / inertia[i]


@njit(cache=True)
def couple_work_plane(y, i, da, nx, nz, fx, fy, dt):
    """The work [J] over dt [s] of the couple da (n x F)_z (da [m], F [N]) on granule i's
    spin at state y."""
    return dt * da * (nx * fy - nz * fx) * y[i, 5]


@njit(cache=True)
def pair_mindlin(p, i, j, ri, rj, yv, yn, h, hist, c, half_shrink, lammps_arms, clip):
    """Mindlin's law at listed pair p (granules i, j of radii ri, rj [m]; history rows
    hist, its coefficient row c) of the plane, as solver.granular3d.mindlin_forces: returns
    (in touch, its force (fx, fy) on i [N], the arms of its torques on i and j [m], stored
    energy [J], energy lost [J], the unit normal (nx, nz)). The arrays alone, not the
    model's tuple: this runs per contact and step."""
    if hist[p, HIST_A] == 0.0 and hist[p, HIST_A_END] == 0.0:  # no history, none begun: out of touch is nothing
        if pair_apart(yv[i, 0], yv[i, 1], ri, yv[j, 0], yv[j, 1], rj):
            return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    delta, nx, nz = pair_overlap(yv[i, 0], yv[i, 1], ri, yv[j, 0], yv[j, 1], rj)
    if delta <= 0.0:
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, mindlin_parted(hist, p, c), nx, nz
    ai = contact_arm(ri, delta, half_shrink)
    aj = contact_arm(rj, delta, half_shrink)
    _, vt = pair_rates(yv[i, 3], yv[i, 4], yv[i, 5], yv[j, 3], yv[j, 4], yv[j, 5], nx, nz, ai, aj)
    ddot = pair_normal_rate(yn[i, 3], yn[i, 4], yn[j, 3], yn[j, 4], nx, nz)
    n_abs = normal_law_force(delta, ddot, c, hist[p, HIST_MAX], hist[p, HIST_RATE], clip)
    a = contact_radius(ri * rj / (ri + rj), delta)
    f0x, f0y, _ = mindlin_old_force(hist, p, c)
    fx, fy, _, e, d = mindlin_contact(hist, p, c, a, delta, nx, nz, 0.0, -vt * nz, vt * nx, 0.0, h, n_abs)
    ti = ai
    tj = aj
    if lammps_arms:  # LAMMPS's torque arms: their couples' extra work over h is lost from D
        ti = ri - 0.5 * delta
        tj = rj - 0.5 * delta
        d -= couple_work_plane(yv, i, ti - ai, nx, nz, f0x + fx, f0y + fy, 0.5 * h)
        d -= couple_work_plane(yv, j, tj - aj, nx, nz, f0x + fx, f0y + fy, 0.5 * h)
    return True, fx, fy, ti, tj, e, d, nx, nz


@njit(cache=True)
def mindlin_forces(yv, yn, h, g, cfg, acc):
    """Mindlin's tangential law (docs/model.md section 3.16) at every listed pair and wall
    contact of the plane whose coefficient row has COEF_KT > 0, after the velocity-Verlet
    force pass, with solver.granular3d.mindlin_forces's signature and meaning: positions
    and the slip rate from yv (the half step's velocities, over h [s]; h = 0: the committed
    history's force), |N| from yn's velocities. Adds the forces and torques to acc[:, 3:6],
    the trial histories into HIST_XI_END, HIST_A_END, HIST_F_END. Returns (the springs'
    stored energy [J], the energy they lost over the step [J])."""
    e_t = 0.0
    lost = 0.0
    mass = g.mass
    inertia = g.inertia
    radius = g.radius
    pair_ij = g.pair_ij
    pair_coef = g.pair_coef
    pair_hist = g.pair_hist
    half_shrink = 0.5 * cfg.arm_shrink
    lammps_arms = cfg.lammps_arms
    clip = cfg.clip
    for p in range(pair_ij.shape[0]):
        c = pair_coef[p]
        if c[COEF_KT] == 0.0:
            continue
        i = pair_ij[p, 0]
        j = pair_ij[p, 1]
        touch, fx, fy, ti, tj, e, d, nx, nz = pair_mindlin(
            p, i, j, radius[i], radius[j], yv, yn, h, pair_hist, c, half_shrink, lammps_arms, clip
        )
        lost += d
        if not touch:
            continue
        e_t += e
        push_tangential_plane(acc, mass, inertia, i, ti, nx, nz, fx, fy, 1.0)
        push_tangential_plane(acc, mass, inertia, j, tj, nx, nz, fx, fy, -1.0)
    e_w, lost_w = wall_mindlin(yv, yn, h, g, cfg, acc)
    return e_t + e_w, lost + lost_w


@njit(cache=True)
def wall_mindlin(yv, yn, h, g, cfg, acc):
    """`mindlin_forces` at the wall contacts: (stored energy [J], energy lost [J])."""
    e_t = 0.0
    lost = 0.0
    mass = g.mass
    inertia = g.inertia
    for w in range(g.wall_i.shape[0]):
        c = g.wall_coef[w]
        if c[COEF_KT] == 0.0:
            continue
        i = g.wall_i[w]
        ri = g.radius[i]
        nx = g.wall_geo[w, 0]
        nz = g.wall_geo[w, 1]
        shift, vn, _ = wall_motion(g, w)
        delta = wall_overlap(yv[i, 0], yv[i, 1], ri, nx, nz, g.wall_geo[w, 2] + shift)
        if delta <= 0.0:
            lost += mindlin_parted(g.wall_hist, w, c)
            continue
        arm = contact_arm(ri, delta, cfg.arm_shrink)
        _, vt = wall_rates(yv[i, 3], yv[i, 4], yv[i, 5], nx, nz, arm)
        ddot = yn[i, 3] * nx + yn[i, 4] * nz - vn
        n_abs = normal_law_force(delta, ddot, c, g.wall_hist[w, HIST_MAX], g.wall_hist[w, HIST_RATE], cfg.clip)
        a = contact_radius(ri, delta)
        fx, fy, _, e, d = mindlin_contact(g.wall_hist, w, c, a, delta, nx, nz, 0.0, -vt * nz, vt * nx, 0.0, h, n_abs)
        e_t += e
        lost += d
        push_tangential_plane(acc, mass, inertia, i, arm, nx, nz, fx, fy, 1.0)
    return e_t, lost

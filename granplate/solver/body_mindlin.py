"""Mindlin's tangential law at the granules' contacts on an elastic body in space
(docs/model.md sections 3.9 and 3.16): the law of the granule-wall contacts
(solver.granular3d's per-contact step, physics.mindlin, eqs. M1-M6) on each granule's
contact with the body's surface, its history in the body's per-granule history rows
(`BodyArrays.hist`, columns HIST_XI..HIST_F_END), which the contact keeps while its patch
moves across faces and the contact lists are rebuilt.

The slip is the granule's contact point's motion over the step (its half step's velocity
and spin, which move it over h) less the surface's there: the patch's weighted mean of
the modes' displacement over the step, Phi (q_n+1 - q_n), with the mean of the patch's
weights at both ends of the step when the granule touched at t_n too. The tangential
force F_t acts on the granule (with its torque a n x F_t) and -F_t on the body, spread
over the same patch weights as the normal force; its damping part is booked with the
slip's work in D_friction (eq. M6), not in D_visc.

Under the RK4 schemes (the implicit scheme's body, solver.body_implicit) the same contacts
take the law in the stages instead (`stage_forces`, solver.mindlin_rk4's staged history):
each stage's slip against the surface's velocity at the stage's modal velocities.
"""

from __future__ import annotations

from granplate.jit import njit

from granplate.model.inputs import GEO_DELTA, GEO_N, GEO_NX, GEO_NY, GEO_NZ, GEO_TOUCH
from granplate.physics.contact import contact_arm
from granplate.physics.laws import keeps_history, tangential_scale, tangential_stiffness
from granplate.physics.space import slip_velocity_3d
from granplate.solver.body_surface import spread, surface_velocity
from granplate.solver.friction_space import apply_friction_impulse
from granplate.solver.granular3d import VX, WX
from granplate.solver.mindlin_history import mindlin_contact, mindlin_parted
from granplate.solver.mindlin_rk4 import stage_apart, stage_contact, sticking_rate


@njit(cache=True)
def has_mindlin(b) -> bool:
    """Whether any granule's contact with the body is under a tangential law with history (Mindlin's; laws.keeps_history)."""
    for i in range(b.coef.shape[0]):
        if keeps_history(b.coef[i]):
            return True
    return False


@njit(cache=True)
def surface_motion(b, buf_old, buf, i, vq):
    """The surface's velocity [m/s] at granule i's contact for the modal rates vq (nm,):
    the patch of buffer buf, averaged with buffer buf_old's where the granule touched there
    too (buf_old != buf)."""
    v0, v1, v2 = surface_velocity(b, buf, i, vq)
    if buf_old != buf and b.geo[buf_old, i, GEO_TOUCH] != 0.0:
        u0, u1, u2 = surface_velocity(b, buf_old, i, vq)
        return 0.5 * (v0 + u0), 0.5 * (v1 + u1), 0.5 * (v2 + u2)
    return v0, v1, v2


@njit(cache=True)
def mindlin_forces(y, vq, b, buf_old, buf, h, radius, mass, inertia, arm_shrink, acc):
    """Mindlin's law at every granule's contact on the body whose coefficient row has
    a tangential law with history (Mindlin's), after the body's force pass into buffer buf (its overlaps, normals, |N|
    and patches): the slip from y's velocities and spins (the half step's) against the
    surface's motion at the modal rates vq (nm,) [(q_n+1 - q_n) / h; h = 0: the force of the
    committed history, vq the modal velocity], over h [s]. Adds F_t / m and the torque's
    a n x F_t / I to acc, -F_t to the modal forces b.fmodal[buf]; the trial histories into
    HIST_XI_END.. of b.hist. Returns (the springs' stored energy [J], the energy they lost
    over the step [J], eq. M6)."""
    e_t = 0.0
    lost = 0.0
    g = b.geo[buf]
    for i in range(b.coef.shape[0]):
        c = b.coef[i]
        if not keeps_history(c):
            continue
        delta = g[i, GEO_DELTA]
        if g[i, GEO_TOUCH] == 0.0 or delta <= 0.0:
            lost += mindlin_parted(b.hist, i, c)
            continue
        arm = contact_arm(radius[i], delta, arm_shrink)
        v0, v1, v2 = surface_motion(b, buf_old, buf, i, vq)
        vsx, vsy, vsz, nx, ny, nz = contact_slip(y, g, i, arm, v0, v1, v2)
        a = tangential_scale(c, radius[i], delta)  # R* = R: the body flat there
        fx, fy, fz, e, d = mindlin_contact(b.hist, i, c, a, delta, nx, ny, nz, vsx, vsy, vsz, h, abs(g[i, GEO_N]))
        e_t += e
        lost += d
        apply_friction_impulse(acc, i, arm, 1.0 / mass[i], 1.0 / inertia[i], nx, ny, nz, fx, fy, fz, 1.0)
        spread(b, buf, i, -fx, -fy, -fz, b.fmodal[buf], 1.0)
    return e_t, lost


@njit(cache=True)
def step_forces(y, q0, q1, b, buf_old, buf, h, radius, mass, inertia, arm_shrink, acc):
    """`mindlin_forces` over a step h > 0 [s] that took the modes from q0 to q1 (nm,): the
    surface's motion at the rates (q1 - q0) / h. Returns (stored energy [J], energy lost [J]);
    (0, 0) at once where no contact is Mindlin's."""
    if not has_mindlin(b):
        return 0.0, 0.0
    vq = b.mrow  # (nm,) scratch: the modes' rates
    for m in range(vq.shape[0]):
        vq[m] = (q1[m] - q0[m]) / h
    return mindlin_forces(y, vq, b, buf_old, buf, h, radius, mass, inertia, arm_shrink, acc)


@njit(cache=True)
def contact_slip(y, g, i, arm, v0, v1, v2):
    """Granule i's slip velocity [m/s] at its contact on the body (its geometry row g[i] of
    one buffer) against the surface's velocity (v0, v1, v2) [m/s] there, and the unit normal
    from the granule into the body."""
    nx = -g[i, GEO_NX]
    ny = -g[i, GEO_NY]
    nz = -g[i, GEO_NZ]
    vsx, vsy, vsz = slip_velocity_3d(
        y[i, VX] - v0,
        y[i, VX + 1] - v1,
        y[i, VX + 2] - v2,
        arm * y[i, WX],
        arm * y[i, WX + 1],
        arm * y[i, WX + 2],
        nx,
        ny,
        nz,
    )
    return vsx, vsy, vsz, nx, ny, nz


@njit(cache=True)
def stage_forces(y, qd, b, buf, radius, mass, inertia, arm_shrink, acc, record):
    """Mindlin's law at an RK4 stage (solver.mindlin_rk4.stage_contact) at every granule's
    contact on the body under a law with history, after the body's force pass into buffer
    buf at granule state y and modal velocities qd (nm,): F_t / m and a n x F_t / I added
    to acc, -F_t to the modal forces b.fmodal[buf]; record: the trial histories (the step's
    end pass). Returns (the springs' energy [J], the power -F_t . v_s [W], the largest
    sticking rate sqrt(k_t / m_t) [1/s])."""
    e_t = 0.0
    p_fric = 0.0
    rate = 0.0
    g = b.geo[buf]
    for i in range(b.coef.shape[0]):
        c = b.coef[i]
        if not keeps_history(c):
            continue
        delta = g[i, GEO_DELTA]
        if g[i, GEO_TOUCH] == 0.0 or delta <= 0.0:
            stage_apart(b.hist, i, record)
            continue
        arm = contact_arm(radius[i], delta, arm_shrink)
        v0, v1, v2 = surface_velocity(b, buf, i, qd)
        vsx, vsy, vsz, nx, ny, nz = contact_slip(y, g, i, arm, v0, v1, v2)
        a = tangential_scale(c, radius[i], delta)  # R* = R: the body flat there
        fx, fy, fz, e = stage_contact(b.hist, i, c, a, delta, nx, ny, nz, vsx, vsy, vsz, g[i, GEO_N], record)
        inv_m = 1.0 / mass[i]
        inv_i = 1.0 / inertia[i]
        apply_friction_impulse(acc, i, arm, inv_m, inv_i, nx, ny, nz, fx, fy, fz, 1.0)
        spread(b, buf, i, -fx, -fy, -fz, b.fmodal[buf], 1.0)
        e_t += e
        p_fric -= fx * vsx + fy * vsy + fz * vsz
        rate = max(rate, sticking_rate(tangential_stiffness(c, a), inv_m + arm * arm * inv_i))
    return e_t, p_fric, rate

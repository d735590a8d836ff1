"""Mindlin's tangential law with history (docs/model.md section 3.16): an elastic
tangential spring of stiffness k_t = 8 G* a on the contact's elastic tangential
displacement xi, capped by Coulomb's limit mu |N|, as LAMMPS's `pair granular ...
tangential mindlin` (with its `mindlin_rescale` rule as the contact radius shrinks).

Per contact and step of length dt (the contact plane's normal n, the slip velocity v_s at
the half step, eqs. M1-M5):

    a = sqrt(R* delta),  k_t = 8 G* a,   1/G* = (2 - nu_1)/G_1 + (2 - nu_2)/G_2     (M1)
    xi <- xi a / a_old  where the contact radius shrank (a < a_old)                 (M2)
    xi <- (xi - (xi.n) n) |xi| / |xi - (xi.n) n|   (into the tangent plane)         (M3)
    xi <- xi + v_s dt,  F_t = -k_t xi - eta_t v_s                                   (M4)
    |F_t| > mu |N|:  F_t <- mu |N| F_t / |F_t|,  xi <- -(F_t + eta_t v_s) / k_t     (M5)

with G = E / (2 (1 + nu)), a rigid body's 1/G = 0, and the optional tangential damping
eta_t = x_t c delta^(1/4) (x_t times eq. 3's normal damping coefficient, LAMMPS's `mindlin
NULL x_t mu`). The spring stores 1/2 k_t |xi|^2; a step loses eq. (M6) (`step_loss`): the
slip's and the damping's work, and what the stiffness's change moves. One small pure function
each, compiled by numba; vectors are passed and returned as their three components.
"""

from __future__ import annotations

import math

import numpy as np

from granplate.jit import njit
from granplate.physics.contact import COEF_C, COEF_KT, COEF_MU, COEF_MUT, COEF_XT

#: LAMMPS's threshold of a frame update (its EPSILON): the history is turned into the new
#: tangent plane only where its normal part carries a force above EPSILON mu |N|.
FRAME_EPSILON = 1e-10


@njit(cache=True)
def shear_modulus(young: float, poisson: float) -> float:
    """G = E / (2 (1 + nu)) [Pa]."""
    return young / (2.0 * (1.0 + poisson))


@njit(entry=True, cache=True)
def tangential_compliance(young: float, poisson: float) -> float:
    """One body's share (2 - nu) / G [1/Pa] of 1 / G* (eq. M1)."""
    return (2.0 - poisson) / shear_modulus(young, poisson)


@njit(entry=True, cache=True)
def mindlin_coefficient(g_star: float) -> float:
    """8 G* [Pa]: the tangential stiffness per unit contact radius, k_t = 8 G* a (eq. M1)."""
    return 8.0 * g_star


@njit(cache=True, inline="always")
def contact_radius(r_star: float, delta: float) -> float:
    """Hertz's contact radius a = sqrt(R* delta) [m] (eq. M1)."""
    return math.sqrt(r_star * delta)


@njit(cache=True, inline="always")
def tangential_damping(x_t: float, c: float, delta: float) -> float:
    """The tangential damping coefficient eta_t = x_t c delta^(1/4) [N s/m]: x_t times eq.
    (3)'s normal damping coefficient c [N s/m^(5/4)] at overlap delta [m] (0 where x_t = 0)."""
    if x_t == 0.0:
        return 0.0
    return x_t * c * math.sqrt(math.sqrt(delta))


@njit(cache=True, inline="always")
def tangential_stiffness(k_per_radius: float, a: float) -> float:
    """k_t = 8 G* a [N/m] from the coefficient 8 G* [Pa] and the contact radius a [m]."""
    return k_per_radius * a


@njit(cache=True, inline="always")
def rescale_history(xx: float, xy: float, xz: float, a: float, a_old: float):
    """Eq. (M2), LAMMPS's `mindlin_rescale`: xi scaled by a / a_old where the contact
    radius a [m] is below its value a_old at the last step (unloading), else unchanged."""
    if a < a_old:
        s = a / a_old
        return xx * s, xy * s, xz * s
    return xx, xy, xz


@njit(cache=True, inline="always")
def rotate_history(xx: float, xy: float, xz: float, nx: float, ny: float, nz: float, k: float, f_crit: float):
    """Eq. (M3): xi's normal part removed and its length kept, where that part's force k
    |xi.n| exceeds FRAME_EPSILON f_crit (k: k_t [N/m], f_crit = mu |N| [N]; as LAMMPS's
    `rotate_rescale_vec`); a xi along n becomes zero."""
    rn = xx * nx + xy * ny + xz * nz
    if not abs(rn) * k > FRAME_EPSILON * f_crit:
        return xx, xy, xz
    length = math.sqrt(xx * xx + xy * xy + xz * xz)
    px = xx - rn * nx
    py = xy - rn * ny
    pz = xz - rn * nz
    proj = math.sqrt(px * px + py * py + pz * pz)
    s = length / proj if proj > 0.0 else 0.0
    return px * s, py * s, pz * s


@njit(cache=True, inline="always")
def spring_energy(k: float, xx: float, xy: float, xz: float) -> float:
    """The tangential spring's stored energy 1/2 k_t |xi|^2 [J]."""
    return 0.5 * k * (xx * xx + xy * xy + xz * xz)


@njit(cache=True, inline="always")
def mindlin_force(xx: float, xy: float, xz: float, k: float, f_crit: float, dx: float, dy: float, dz: float):
    """Eqs. (M4)-(M5) after the increment: the tangential force F_t = -k_t xi + F_d on the
    first body (F_d (3): the damping force -eta_t v_s [N]), capped at f_crit = mu |N| [N]
    with xi reset to -(F_t - F_d) / k_t (LAMMPS's rule; a zero xi gives no force). Returns
    (F_t (3) [N], the new xi (3) [m])."""
    fx = -k * xx + dx
    fy = -k * xy + dy
    fz = -k * xz + dz
    mag = math.sqrt(fx * fx + fy * fy + fz * fz)
    if mag <= f_crit:
        return fx, fy, fz, xx, xy, xz
    if xx == 0.0 and xy == 0.0 and xz == 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    s = f_crit / mag
    fx *= s
    fy *= s
    fz *= s
    return fx, fy, fz, -(fx - dx) / k, -(fy - dy) / k, -(fz - dz) / k


@njit(cache=True, inline="always")
def mindlin_step(
    xx: float,
    xy: float,
    xz: float,
    a: float,
    a_old: float,
    k_per_radius: float,
    nx: float,
    ny: float,
    nz: float,
    vx: float,
    vy: float,
    vz: float,
    dt: float,
    f_crit: float,
    damp: float,
    f0x: float,
    f0y: float,
    f0z: float,
):
    """One contact's step of eqs. (M2)-(M5): its history xi (3) [m] and contact radius
    a_old [m] at the last step, its contact radius a [m] now, 8 G* [Pa], the unit normal
    n, the slip velocity v_s (3) [m/s] over the step dt [s] (0: the force at the last
    step's history, turned into the plane of n), the Coulomb limit f_crit = mu |N| [N], the
    tangential damping coefficient eta_t [N s/m] and the last step's force F_old (3) [N].
    Returns (F_t (3) on the first body [N], the new xi (3) [m], the spring's energy 1/2 k_t
    |xi|^2 [J], the energy lost over the step [J], eq. M6)."""
    e_old = spring_energy(tangential_stiffness(k_per_radius, a_old), xx, xy, xz)
    k = tangential_stiffness(k_per_radius, a)
    xx, xy, xz = rescale_history(xx, xy, xz, a, a_old)
    xx, xy, xz = rotate_history(xx, xy, xz, nx, ny, nz, k, f_crit)
    fx, fy, fz, xx, xy, xz = mindlin_force(
        xx + dt * vx, xy + dt * vy, xz + dt * vz, k, f_crit, -damp * vx, -damp * vy, -damp * vz
    )
    e_new = spring_energy(k, xx, xy, xz)
    return fx, fy, fz, xx, xy, xz, e_new, step_loss(f0x, f0y, f0z, fx, fy, fz, vx * dt, vy * dt, vz * dt, e_old, e_new)


@njit(cache=True, inline="always")
def step_loss(f0x, f0y, f0z, fx, fy, fz, sx, sy, sz, e_old: float, e_new: float) -> float:
    """Eq. (M6): the energy a contact lost over a step [J], the work its slip s (3) [m] did
    against the tangential force by the trapezoidal rule (F_old, F_new on the first body
    [N]: the velocity-Verlet kicks' work on the granules to second order) less the rise of
    the spring's energy e_new - e_old [J]: the slip work of (M5), and the energy the
    stiffness's change and the rescale (M2) take out (or, while the contact radius grows,
    put in) at fixed xi."""
    work = -0.5 * ((f0x + fx) * sx + (f0y + fy) * sy + (f0z + fz) * sz)
    return work - (e_new - e_old)


@njit(cache=True, inline="always")
def stage_force(
    xx: float,
    xy: float,
    xz: float,
    a: float,
    a_old: float,
    k_per_radius: float,
    nx: float,
    ny: float,
    nz: float,
    ix: float,
    iy: float,
    iz: float,
    vx: float,
    vy: float,
    vz: float,
    f_crit: float,
    damp: float,
):
    """Eqs. (M2)-(M5) at one stage of a multi-stage step (RK4, docs/model.md section 3.16):
    the committed history xi (3) [m] of contact radius a_old [m], rescaled to the stage's
    contact radius a [m] and turned into the plane of its normal n, moved on by the
    increment (ix, iy, iz) [m] the slip has made since the step's start (its normal part
    removed), damped by eta_t = damp [N s/m] on the stage's slip velocity v (3) [m/s] and
    capped at f_crit = mu |N| [N]. Returns (F_t (3) on the first body [N], xi (3) [m], the
    spring's energy 1/2 k_t |xi|^2 [J])."""
    k = tangential_stiffness(k_per_radius, a)
    xx, xy, xz = rescale_history(xx, xy, xz, a, a_old)
    xx, xy, xz = rotate_history(xx, xy, xz, nx, ny, nz, k, f_crit)
    i_n = ix * nx + iy * ny + iz * nz
    fx, fy, fz, xx, xy, xz = mindlin_force(
        xx + ix - i_n * nx,
        xy + iy - i_n * ny,
        xz + iz - i_n * nz,
        k,
        f_crit,
        -damp * vx,
        -damp * vy,
        -damp * vz,
    )
    return fx, fy, fz, xx, xy, xz, spring_energy(k, xx, xy, xz)


# -- Mindlin's law as a registered tangential law with history (physics.laws dispatches on
# its id; docs/architecture.md, "Adding a tangential law"). The common arguments: the
# contact's coefficient row `coef` (physics.contact's columns: 8 G* in COEF_KT, mu in
# COEF_MUT, x_t in COEF_XT), its overlap delta [m] and |N| = n_abs [N], its history xi (3)
# [m] with the scale `a_old` [m] it was stored at (Mindlin's: the contact radius), the scale
# `a` now (`law_scale`), the unit normal n (3) and the slip velocity v (3) [m/s].


@njit(cache=True, inline="always")
def law_scale(coef, r_star: float, delta: float) -> float:
    """The scale the history is stored at, at overlap delta [m] of a contact of R* [m]: the
    contact radius a = sqrt(R* delta) [m] (eq. M1)."""
    return contact_radius(r_star, delta)


@njit(cache=True, inline="always")
def law_stiffness(coef, a: float) -> float:
    """The sticking contact's tangential stiffness k_t = 8 G* a [N/m] (eq. M1)."""
    return tangential_stiffness(coef[COEF_KT], a)


@njit(cache=True, inline="always")
def law_energy(coef, a: float, xx: float, xy: float, xz: float) -> float:
    """The energy the history xi (3) [m] stores at scale a [m]: 1/2 k_t |xi|^2 [J]."""
    return spring_energy(tangential_stiffness(coef[COEF_KT], a), xx, xy, xz)


@njit(cache=True, inline="always")
def law_step(xx, xy, xz, a, a_old, coef, delta, nx, ny, nz, vx, vy, vz, dt, n_abs, f0x, f0y, f0z):
    """One step of dt [s] (`mindlin_step`, eqs. M2-M6) with the tangential damping
    eta_t = x_t c delta^(1/4) and the Coulomb limit mu |N|; f0 (3): the last step's force [N].
    Returns (F_t (3) on the first body [N], the new xi (3) [m], stored energy [J], energy
    lost over the step [J])."""
    damp = tangential_damping(coef[COEF_XT], coef[COEF_C], delta)
    return mindlin_step(
        xx, xy, xz, a, a_old, coef[COEF_KT], nx, ny, nz, vx, vy, vz, dt, coef[COEF_MUT] * n_abs, damp, f0x, f0y, f0z
    )


@njit(cache=True, inline="always")
def law_stage(xx, xy, xz, a, a_old, coef, delta, nx, ny, nz, ix, iy, iz, vx, vy, vz, n_abs):
    """The force at one stage of a multi-stage step (`stage_force`): the committed history
    moved on by the increment i (3) [m] the slip made since the step's start, damped on the
    stage's slip velocity v (3). Returns (F_t (3) [N], xi (3) [m], stored energy [J])."""
    damp = tangential_damping(coef[COEF_XT], coef[COEF_C], delta)
    return stage_force(
        xx, xy, xz, a, a_old, coef[COEF_KT], nx, ny, nz, ix, iy, iz, vx, vy, vz, coef[COEF_MUT] * n_abs, damp
    )


def law_columns(coef: np.ndarray, compliance: np.ndarray, contact) -> None:
    """Rows of `coef` made Mindlin's in place: 8 G* from 1 / G* = `compliance` [1/Pa] (per
    row, eq. M1) into COEF_KT, the Coulomb coefficient moved from COEF_MU (which the rate
    laws read: the rate passes then pass these rows by) to COEF_MUT, the tangential damping
    factor x_t (contact.tangential_damping) into COEF_XT."""
    coef[:, COEF_KT] = mindlin_coefficient(1.0) / compliance
    coef[:, COEF_MUT] = coef[:, COEF_MU]
    coef[:, COEF_MU] = 0.0
    coef[:, COEF_XT] = contact.tangential_damping

"""Mindlin's tangential law in its incremental form, with the elastic tangential force as
history (docs/model.md section 3.16, "The force form"; LAMMPS's `pair granular ...
tangential mindlin_rescale/force`, after Thornton, Cummins & Cleary, Powder Technol. 233
(2013) 30-46, eq. 18): a registered tangential law with history, the interface of physics.mindlin.

Where Mindlin's law (physics.mindlin) keeps the tangential displacement xi and gives the
force -k_t xi with the current stiffness, this form keeps the elastic force F_e itself and
adds each step's increment with the stiffness of that step (eq. M4f):

    F_e <- F_e a / a_old  where the contact radius shrank (a < a_old)            (M2)
    F_e <- (F_e - (F_e.n) n) |F_e| / |F_e - (F_e.n) n|                           (M3)
    F_e <- F_e - k_t v_s dt,  k_t = 8 G* a,  F_t = F_e - eta_t v_s              (M4f)
    |F_t| > mu |N|:  F_t <- mu |N| F_t / |F_t|,  F_e <- F_t + eta_t v_s         (M5f)

Under a constant contact radius both forms give the same force; while the overlap changes
they differ (the displacement form is path independent in k_t, the incremental form is
not), which is what the two LAMMPS options show. The spring stores |F_e|^2 / (2 k_t); a step
loses the slip's and the damping's work less that energy's rise (eq. M6, `step_loss`).
"""

from __future__ import annotations

import numpy as np

from granplate.jit import njit
from granplate.physics.contact import COEF_C, COEF_KT, COEF_MUT, COEF_XT
from granplate.physics.mindlin import law_scale as law_scale  # the contact radius, as Mindlin's
from granplate.physics.mindlin import law_stiffness as law_stiffness  # 8 G* a, as Mindlin's
from granplate.physics.mindlin import (
    mindlin_force,
    rescale_history,
    rotate_history,
    step_loss,
    tangential_damping,
    tangential_stiffness,
)
from granplate.physics.mindlin import law_columns as mindlin_columns

#: mindlin_force's stiffness argument that makes its history the elastic force itself
#: (F = -k xi with k = -1: F = xi; a capped history xi = -(F_t - F_d) / k = F_t - F_d, eq. M5f)
FORCE_HISTORY = -1.0


@njit(cache=True)
def force_energy(k: float, fx: float, fy: float, fz: float) -> float:
    """The energy |F_e|^2 / (2 k_t) [J] of the elastic tangential force F_e (3) [N] at the
    stiffness k_t = k [N/m] (0 without stiffness)."""
    if k <= 0.0:
        return 0.0
    return 0.5 * (fx * fx + fy * fy + fz * fz) / k


@njit(cache=True, inline="always")
def law_energy(coef, a: float, fx: float, fy: float, fz: float) -> float:
    """The energy the elastic force F_e (3) [N] stores at contact radius a: |F_e|^2 / (2 k_t) [J]."""
    return force_energy(tangential_stiffness(coef[COEF_KT], a), fx, fy, fz)


@njit(cache=True)
def increment_force(fx, fy, fz, a, a_old, k, nx, ny, nz, dx, dy, dz, f_crit, damp, vx, vy, vz):
    """Eqs. M2-M5f from the elastic force F_e (3) [N] at contact radius a_old to a, turned
    into the plane of n, moved on by -k_t times the slip increment d (3) [m] (in that plane),
    damped on v (3) [m/s] and capped at f_crit [N]. Returns (F_t (3), F_e (3))."""
    fx, fy, fz = rescale_history(fx, fy, fz, a, a_old)
    fx, fy, fz = rotate_history(fx, fy, fz, nx, ny, nz, 1.0, f_crit)  # LAMMPS's frame test on the force
    return mindlin_force(
        fx - k * dx,
        fy - k * dy,
        fz - k * dz,
        FORCE_HISTORY,
        f_crit,
        -damp * vx,
        -damp * vy,
        -damp * vz,
    )


@njit(cache=True, inline="always")
def law_step(xx, xy, xz, a, a_old, coef, delta, nx, ny, nz, vx, vy, vz, dt, n_abs, f0x, f0y, f0z):
    """One step of dt [s] from the history F_e = (xx, xy, xz) [N] (eqs. M2-M5f, M6); f0 (3):
    the last step's force [N]. Returns (F_t (3) on the first body [N], the new F_e (3) [N],
    stored energy [J], energy lost over the step [J])."""
    e_old = force_energy(tangential_stiffness(coef[COEF_KT], a_old), xx, xy, xz)
    k = tangential_stiffness(coef[COEF_KT], a)
    damp = tangential_damping(coef[COEF_XT], coef[COEF_C], delta)
    fx, fy, fz, xx, xy, xz = increment_force(
        xx, xy, xz, a, a_old, k, nx, ny, nz, vx * dt, vy * dt, vz * dt, coef[COEF_MUT] * n_abs, damp, vx, vy, vz
    )
    e_new = force_energy(k, xx, xy, xz)
    return fx, fy, fz, xx, xy, xz, e_new, step_loss(f0x, f0y, f0z, fx, fy, fz, vx * dt, vy * dt, vz * dt, e_old, e_new)


@njit(cache=True, inline="always")
def law_stage(xx, xy, xz, a, a_old, coef, delta, nx, ny, nz, ix, iy, iz, vx, vy, vz, n_abs):
    """The force at one stage of a multi-stage step: the committed F_e moved on by -k_t (of
    the stage's contact radius a) times the increment i (3) [m] the slip made since the
    step's start. Returns (F_t (3) [N], F_e (3) [N], stored energy [J])."""
    k = tangential_stiffness(coef[COEF_KT], a)
    damp = tangential_damping(coef[COEF_XT], coef[COEF_C], delta)
    i_n = ix * nx + iy * ny + iz * nz  # the increment's normal part removed, as physics.mindlin.stage_force
    fx, fy, fz, xx, xy, xz = increment_force(
        xx,
        xy,
        xz,
        a,
        a_old,
        k,
        nx,
        ny,
        nz,
        ix - i_n * nx,
        iy - i_n * ny,
        iz - i_n * nz,
        coef[COEF_MUT] * n_abs,
        damp,
        vx,
        vy,
        vz,
    )
    return fx, fy, fz, xx, xy, xz, force_energy(k, xx, xy, xz)


def law_columns(coef: np.ndarray, compliance: np.ndarray, contact) -> None:
    """Mindlin's columns (physics.mindlin.law_columns): 8 G*, mu in COEF_MUT, x_t."""
    mindlin_columns(coef, compliance, contact)

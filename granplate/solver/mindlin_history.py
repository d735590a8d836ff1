"""A contact's Mindlin history in the velocity-Verlet force passes (docs/model.md section
3.16), in either dimension (the plane passes its vectors with z = 0): the law's step over
h from the committed history to the trial one (physics.mindlin.mindlin_step, with the
tangential damping), the force of the last step, and the end of a parted contact's history.
The pair and wall passes of the plane (solver.mindlin_plane), of space (solver.granular3d,
solver.mindlin_space) and of the elastic body (solver.body_mindlin) call these.

Where the trial goes is told by the history row's width (`trial_column`): a row of N_HIST
columns keeps it apart (HIST_XI_END to HIST_F_END, taken in by the commit: the elastic
body's rows, and rows stored by a run that kept them), a row of N_HIST_STEP columns (the
granular contacts under velocity Verlet, whose every step is accepted) is moved on in place.
The numbers are the same either way.
"""

from __future__ import annotations


from granplate.jit import njit

from granplate.model.inputs import HIST_A, HIST_A_END, HIST_F, HIST_XI, HIST_XI_END, N_MINDLIN
from granplate.physics.laws import tangential_energy, tangential_step

#: offsets of the contact radius and the force in a Mindlin history (committed or trial)
_A, _F = HIST_A - HIST_XI, HIST_F - HIST_XI


@njit(cache=True, inline="always")
def trial_column(hist) -> int:
    """The first column of a contact's trial history: HIST_XI_END in rows that keep the
    trial apart (N_HIST columns), HIST_XI in rows moved on in place (N_HIST_STEP)."""
    return HIST_XI_END if hist.shape[1] > HIST_XI_END else HIST_XI


@njit(cache=True, inline="always")
def mindlin_touched(hist, k) -> bool:
    """Whether contact k holds a Mindlin history, committed or trial (a contact radius)."""
    return hist[k, HIST_A] != 0.0 or (hist.shape[1] > HIST_A_END and hist[k, HIST_A_END] != 0.0)


@njit(cache=True, inline="always")
def record_trial(hist, k, xx, xy, xz, a, fx, fy, fz) -> None:
    """Contact k's trial history from `trial_column` on: its tangential displacement xi (3)
    [m], its contact radius a [m] and its force F_t (3) [N]."""
    base = trial_column(hist)
    hist[k, base] = xx
    hist[k, base + 1] = xy
    hist[k, base + 2] = xz
    hist[k, base + _A] = a
    hist[k, base + _F] = fx
    hist[k, base + _F + 1] = fy
    hist[k, base + _F + 2] = fz


@njit(cache=True, inline="always")
def mindlin_contact(hist, k, c, a, delta, nx, ny, nz, vsx, vsy, vsz, h, n_abs):
    """Contact k (history row hist[k], coefficient row c) under Mindlin's law over the step
    h [s] (physics.mindlin.mindlin_step) at overlap delta and contact radius a [m] and |N| =
    n_abs [N], damped by eta_t = x_t c delta^(1/4); its trial history from `trial_column`
    on. h = 0 (the force pass at t_n of a run's first step): a contact
    with a committed history (a restart) takes its committed force back, as the run that
    stored it had it; a new one its force from the state, which becomes its committed force
    (what the first kick applies). Returns (F_t (3) [N], stored energy [J], energy lost [J])."""
    apart = trial_column(hist) != HIST_XI
    if h == 0.0 and hist[k, HIST_A] > 0.0:
        if apart:
            for col in range(N_MINDLIN):
                hist[k, HIST_XI_END + col] = hist[k, HIST_XI + col]
        e_t = tangential_energy(c, hist[k, HIST_A], hist[k, HIST_XI], hist[k, HIST_XI + 1], hist[k, HIST_XI + 2])
        return hist[k, HIST_F], hist[k, HIST_F + 1], hist[k, HIST_F + 2], e_t, 0.0
    fx, fy, fz, xx, xy, xz, e_t, lost = tangential_step(
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
        vsx,
        vsy,
        vsz,
        h,
        abs(n_abs),
        hist[k, HIST_F],
        hist[k, HIST_F + 1],
        hist[k, HIST_F + 2],
    )
    record_trial(hist, k, xx, xy, xz, a, fx, fy, fz)
    if h == 0.0 and apart:
        for col in range(3):
            hist[k, HIST_F + col] = hist[k, HIST_XI_END + _F + col]
    return fx, fy, fz, e_t, lost


@njit(cache=True, inline="always")
def mindlin_old_force(hist, k, c):
    """The tangential force on the first body at contact k's last step [N] (3)."""
    return hist[k, HIST_F], hist[k, HIST_F + 1], hist[k, HIST_F + 2]


@njit(cache=True, inline="always")
def mindlin_parted(hist, k, c):
    """Contact k has parted: its trial history zero (a new touch starts unloaded, as
    LAMMPS's); returns the spring energy it held [J] (lost)."""
    a_old = hist[k, HIST_A]
    e_old = tangential_energy(c, a_old, hist[k, HIST_XI], hist[k, HIST_XI + 1], hist[k, HIST_XI + 2])
    base = trial_column(hist)
    for col in range(N_MINDLIN):
        hist[k, base + col] = 0.0
    return e_old

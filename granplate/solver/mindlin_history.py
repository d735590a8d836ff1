"""A contact's Mindlin history in the velocity-Verlet force passes (docs/model.md section
3.16), in either dimension (the plane passes its vectors with z = 0): the law's step over
h from the committed history to the trial one (physics.mindlin.mindlin_step, with the
tangential damping), the force of the last step, and the end of a parted contact's history.
The pair and wall passes of the plane (solver.mindlin_plane), of space (solver.granular3d,
solver.mindlin_space) and of the elastic body (solver.body_mindlin) call these.
"""

from __future__ import annotations


from granplate.jit import njit

from granplate.model.inputs import HIST_A, HIST_A_END, HIST_F, HIST_F_END, HIST_XI, HIST_XI_END, N_MINDLIN
from granplate.physics.laws import tangential_energy, tangential_step


@njit(cache=True, inline="always")
def record_trial(hist, k, xx, xy, xz, a, fx, fy, fz) -> None:
    """Contact k's trial history: its tangential displacement xi (3) [m] into HIST_XI_END,
    its contact radius a [m] into HIST_A_END and its force F_t (3) [N] into HIST_F_END."""
    hist[k, HIST_XI_END] = xx
    hist[k, HIST_XI_END + 1] = xy
    hist[k, HIST_XI_END + 2] = xz
    hist[k, HIST_A_END] = a
    hist[k, HIST_F_END] = fx
    hist[k, HIST_F_END + 1] = fy
    hist[k, HIST_F_END + 2] = fz


@njit(cache=True, inline="always")
def mindlin_contact(hist, k, c, a, delta, nx, ny, nz, vsx, vsy, vsz, h, n_abs):
    """Contact k (history row hist[k], coefficient row c) under Mindlin's law over the step
    h [s] (physics.mindlin.mindlin_step) at overlap delta and contact radius a [m] and |N| =
    n_abs [N], damped by eta_t = x_t c delta^(1/4); its trial history into HIST_XI_END,
    HIST_A_END, HIST_F_END. h = 0 (the force pass at t_n of a run's first step): a contact
    with a committed history (a restart) takes its committed force back, as the run that
    stored it had it; a new one its force from the state, which becomes its committed force
    (what the first kick applies). Returns (F_t (3) [N], stored energy [J], energy lost [J])."""
    if h == 0.0 and hist[k, HIST_A] > 0.0:
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
    if h == 0.0:
        for col in range(3):
            hist[k, HIST_F + col] = hist[k, HIST_F_END + col]
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
    for col in range(N_MINDLIN):
        hist[k, HIST_XI_END + col] = 0.0
    return e_old

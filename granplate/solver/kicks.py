"""The velocity-Verlet kicks and drift over a range of granules (docs/model.md section
6.5): the serial loop takes every granule, the threaded one (solver.blocks) one block each.
"""

from __future__ import annotations

from granplate.jit import njit


@njit(cache=True)
def half_kick(v0: float, a: float, hk: float):
    """A half kick over hk [s] from velocity v0 with acceleration a: (v0 + hk a, the change
    hk a, hk (v0 + hk a / 2): the mean velocity times hk, by which a force's work over the
    kick is that force times it [m])."""
    dv = hk * a
    return v0 + dv, dv, hk * (v0 + 0.5 * dv)


@njit(cache=True)
def kick_drift(
    y0, y, acc, fdamp, fload, h, ypred, n_drift, lo, hi, predict=True, loads=True, damped=True, clear=False, w_load=0.0,
    w_damp=0.0,
):  # fmt: skip
    """Granules lo..hi-1 from state y0 into y (y0 may be y itself: each entry is read before
    it is written; another array spares the step a copy of the state): the first half kick
    v = v0 + h/2 a (every column from n_drift on), the drift x = x0 + h v (the columns
    before), and the state the force pass reads into ypred:
    the new positions, and the velocities predicted at the end, v + h/2 a (predict False:
    the half step's v, as LAMMPS's force pass reads them; solver.verlet_damping). Returns
    (the load's work, the damping force's work) of the kick [J]: h/2 F (v_before + v_after)/2.
    fload (fdamp) is not read where `loads` (`damped`) is False: the caller knows it is all
    zero, and its work is then 0 exactly as the sum would give. `clear`: each acceleration
    of the kicked columns is set to zero once read (the step's force pass then writes the
    new ones into acc without clearing it first: solver.clearing.clear_rows). The works are
    added in granule order to w_load and w_damp (those of granules before lo: a range's
    sums carried on, bit for bit those of one call over the ranges together)."""
    hk = 0.5 * h
    for i in range(lo, hi):
        for c in range(n_drift, y.shape[1]):
            v1, dv, vm = half_kick(y0[i, c], acc[i, c], hk)
            if clear:
                acc[i, c] = 0.0
            if loads:
                w_load += fload[i, c] * vm
            if damped:
                w_damp += fdamp[i, c] * vm
            y[i, c] = v1
            ypred[i, c] = v1 + dv if predict else v1
        for c in range(n_drift):
            y[i, c] = y0[i, c] + h * y[i, c + n_drift]
            ypred[i, c] = y[i, c]
    return w_load, w_damp


@njit(cache=True, inline="always")
def closing_rows(
    y, acc, fdamp, fload, hk, dy, n_drift, lo, hi, loads, damped, divide, n_move, mass, inertia, w_load, w_damp
):
    """The closing half kick of granules lo..hi-1 (`kick`), where `divide` from forces and
    torques in acc made accelerations first (`divide_kick`: the first n_move velocity
    columns by mass, the others by inertia; else mass and inertia are not read); the works
    added to w_load and w_damp as `kick_drift` adds them."""
    for i in range(lo, hi):
        for c in range(n_drift, y.shape[1]):
            a = acc[i, c]
            if divide:
                a = a / (mass[i] if c < n_drift + n_move else inertia[i])
                acc[i, c] = a
            v1, _, vm = half_kick(y[i, c], a, hk)
            if loads:
                w_load += fload[i, c] * vm
            if damped:
                w_damp += fdamp[i, c] * vm
            y[i, c] = v1
        for c in range(n_drift):
            dy[i, c] = y[i, c + n_drift]
    return w_load, w_damp


@njit(cache=True)
def kick(y, acc, fdamp, fload, hk, dy, n_drift, lo, hi, loads=True, damped=True, w_load=0.0, w_damp=0.0):
    """Granules lo..hi-1: the closing half kick v += hk a (hk = h/2); dy (the loop's
    derivative at the end of the step) gets the end velocities as the rates of the
    drifting columns. Returns the load's and the damping force's work [J] as `kick_drift`
    (`loads`, `damped`, the carried sums w_load and w_damp as there)."""
    none = y[:0, 0]  # (no masses: not read)
    return closing_rows(
        y, acc, fdamp, fload, hk, dy, n_drift, lo, hi, loads, damped, False, 0, none, none, w_load, w_damp
    )


@njit(cache=True)
def divide_kick(
    y,
    acc,
    fdamp,
    fload,
    hk,
    dy,
    n_drift,
    n_move,
    mass,
    inertia,
    lo,
    hi,
    loads=True,
    damped=True,
    w_load=0.0,
    w_damp=0.0,
):
    """`kick` from the force pass's forces and torques in acc [N, N m] (a pass that left
    its division to the kick): each made an acceleration in acc as the pass would have made
    it (the first n_move velocity columns divided by the mass [kg], the others by the
    moment of inertia [kg m^2]) and the kick taken with it, bit for bit `kick` after the
    pass's division, in one pass over the rows instead of two."""
    return closing_rows(
        y, acc, fdamp, fload, hk, dy, n_drift, lo, hi, loads, damped, True, n_move, mass, inertia, w_load, w_damp
    )

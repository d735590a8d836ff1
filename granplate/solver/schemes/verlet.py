"""Velocity Verlet of the granules (docs/model.md section 6.5), LAMMPS's integrator: one
evaluation of the normal forces per step, the friction at granule-granule and
granule-wall contacts split off exactly per contact, for granular runs without a plate.

One step t -> t + h (fixed h = time.dt_max, cut to land on the output times):
1. friction alone over the time it is owed, h_prev/2 + h/2 (`friction_flow`: the closing
   half step of the last step and the opening half step of this one merged, at the same
   positions), each pass in the reverse contact order of the one before;
2. kick: v += h/2 a_n; drift: x += h v (x, y, theta in the plane; x, y, z in space);
3. one force pass at t + h (`normal_forces`): the normal forces with the damping of
   eq. (3) at the predicted end velocities v + h/2 a_n (second order, where LAMMPS's
   half-step velocities are first order), the shock on the loaded granules;
4. kick: v += h/2 a_n+1; on a step that lands on an output time, the closing friction
   half step (in the reverse order) so that the recorded state is the whole step's.

The work of each kick is booked exactly as the kinetic energy it adds: h/2 F v_mean for
the damping part of the force (D_visc) and the load (E_shock), so eq. (11)'s residual is
Verlet's own energy error, O(h^2), which the loop checks at every step.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from granplate.model.inputs import STATE_COLUMNS
from granplate.physics.contact import COEF_MU
from granplate.solver.dimension import friction_flow, normal_forces
from granplate.solver.ladder import step_to_output

NAME = "verlet"
#: the state's leading columns that drift (x, y, theta in the plane; x, y, z in space),
#: each at the rate held N_DRIFT columns to its right; the columns from N_DRIFT on are
#: velocities and spins, which the kicks change.
N_DRIFT = 3
#: the scratch's per-granule arrays have room for the widest state (space's).
N_COLUMNS = max(STATE_COLUMNS.values())
#: columns of Scratch.split: friction time owed [s], order of the next friction pass
#: (1: forward), whether the planned step lands on an output time, whether the forces at
#: t_n are known (0 until the first step), which of the two buffers holds t_n's.
OWED, FORWARD, LAND, STARTED, CURRENT = range(5)


class Scratch(NamedTuple):
    """The Verlet scheme's own scratch: per-granule damping forces and loads at t_n and at
    the trial step's end (two buffers, swapped on commit), and the split's bookkeeping."""

    fdamp: np.ndarray  # (2, ng, N_COLUMNS) damping force on each granule [N] (velocity columns)
    fload: np.ndarray  # (2, ng, N_COLUMNS) shock load on each granule [N, N m]
    split: np.ndarray  # (5,) OWED, FORWARD, LAND, STARTED, CURRENT


def new_scratch(ng: int, nm: int, nk: int) -> Scratch:
    """Scratch for ng granules (nm modes, nk plate contacts: none are used)."""
    split = np.zeros(5)
    split[FORWARD] = 1.0
    return Scratch(fdamp=np.zeros((2, ng, N_COLUMNS)), fload=np.zeros((2, ng, N_COLUMNS)), split=split)


@njit(cache=True)
def plan(sw, count, cfg, pos, rem):
    """The fixed step dt_max (level 0), cut to land on the next output time `rem` [s]
    away (the remainder, or half of it when it is under two steps). Returns (level, h,
    slot, land)."""
    h, slot, land = step_to_output(0, rem, True, cfg)
    sw.split[LAND] = 1.0 if land else 0.0
    return 0, h, slot, land


@njit(cache=True)
def prepare_level(sw, h, p, slot):
    """Nothing: no plate."""
    return


@njit(cache=True)
def has_friction(g) -> bool:
    """Whether any listed pair or wall contact has a friction coefficient."""
    for p in range(g.pair_coef.shape[0]):
        if g.pair_coef[p, COEF_MU] != 0.0:
            return True
    for w in range(g.wall_coef.shape[0]):
        if g.wall_coef[w, COEF_MU] != 0.0:
            return True
    return False


@njit(cache=True)
def kick_drift(y, acc, fdamp, fload, h, ypred):
    """The first half kick v += h/2 a (every column from N_DRIFT on), the drift x += h v
    (the columns before), and the state the force pass reads into ypred: the new
    positions, and the velocities predicted at the end, v + h/2 a. Returns (the load's
    work, the damping force's work) of the kick [J]: h/2 F (v_before + v_after)/2."""
    hk = 0.5 * h
    w_load = 0.0
    w_damp = 0.0
    for i in range(y.shape[0]):
        for c in range(N_DRIFT, y.shape[1]):
            v0 = y[i, c]
            dv = hk * acc[i, c]
            v1 = v0 + dv
            vm = hk * (v0 + 0.5 * dv)
            w_load += fload[i, c] * vm
            w_damp += fdamp[i, c] * vm
            y[i, c] = v1
            ypred[i, c] = v1 + dv
        for c in range(N_DRIFT):
            y[i, c] += h * y[i, c + N_DRIFT]
            ypred[i, c] = y[i, c]
    return w_load, w_damp


@njit(cache=True)
def kick(y, acc, fdamp, fload, hk, dy):
    """The closing half kick v += hk a (hk = h/2); dy (the loop's derivative at the end of
    the step) gets the end velocities as the rates of the drifting columns. Returns the
    load's and the damping force's work [J] as `kick_drift`."""
    w_load = 0.0
    w_damp = 0.0
    for i in range(y.shape[0]):
        for c in range(N_DRIFT, y.shape[1]):
            v0 = y[i, c]
            dv = hk * acc[i, c]
            vm = hk * (v0 + 0.5 * dv)
            w_load += fload[i, c] * vm
            w_damp += fdamp[i, c] * vm
            y[i, c] = v0 + dv
        for c in range(N_DRIFT):
            dy[i, c] = y[i, c + N_DRIFT]
    return w_load, w_damp


@njit(cache=True)
def attempt(sw, t, h, slot, st, g, p, cfg, w):
    """One Verlet step from st.y into w.ynew (see the module docstring): the trial's
    accelerations at t + h into w.kend, the load's, damping's, friction's and plastic work
    into w.dacc, the largest overlap into w.ovl_new / w.ovl_who. Always converged, one
    force pass. Returns (True, 1, -1, stored energy at t + h [J], 0)."""
    y = w.ynew
    for i in range(y.shape[0]):
        for c in range(y.shape[1]):
            y[i, c] = st.y[i, c]
    cur = int(sw.split[CURRENT])
    nxt = 1 - cur
    if sw.split[STARTED] == 0.0:  # the first step: t_n's forces, loads and damping (st.k1 as `initialise` has it)
        normal_forces(t, st.y, g, cfg, st.k1, sw.fdamp[cur], sw.fload[cur])
    hk = 0.5 * h
    friction = has_friction(g)
    forward = sw.split[FORWARD] != 0.0
    fric = 0.0
    if friction:
        fric = friction_flow(y, sw.split[OWED] + hk, g, cfg, forward)
    wl, wd = kick_drift(y, st.k1, sw.fdamp[cur], sw.fload[cur], h, w.ytmp)
    pr = normal_forces(t + h, w.ytmp, g, cfg, w.kend, sw.fdamp[nxt], sw.fload[nxt])
    wl2, wd2 = kick(y, w.kend, sw.fdamp[nxt], sw.fload[nxt], hk, w.kend)
    if friction and sw.split[LAND] != 0.0:  # an output time: the closing half step
        fric += friction_flow(y, hk, g, cfg, not forward)
    w.dacc[0] = wl + wl2
    w.dacc[1] = -(wd + wd2)
    w.dacc[2] = fric
    w.dacc[3] = pr.w_plastic
    w.pend[0] = pr.p_shock
    w.pend[1] = pr.p_visc
    w.pend[2] = 0.0
    w.ovl_new[0] = pr.ovl
    w.ovl_who[0] = pr.ovl_i
    w.ovl_who[1] = pr.ovl_j
    return True, 1, -1, pr.e_pot, 0.0


@njit(cache=True)
def judge(sw, t, h, slot, level, ratio, e_pot, st, g, p, cfg, w):
    """Every step is accepted (a fixed step). Returns (0, -1, 0, 0)."""
    return 0.0, -1, 0.0, 0.0


@njit(cache=True)
def commit(sw, t, h, slot, plate_work, fric_work, st, g, p, cfg, w):
    """The trial's end forces become t_n's (the buffers swap); the friction owed is half
    this step, or nothing when it landed on an output time; each friction pass made
    reverses the order of the next. Returns the plate work: 0 (no plate)."""
    sw.split[CURRENT] = 1.0 - sw.split[CURRENT]
    sw.split[STARTED] = 1.0
    land = sw.split[LAND] != 0.0
    if not land:
        sw.split[FORWARD] = 1.0 - sw.split[FORWARD]
    sw.split[OWED] = 0.0 if land else 0.5 * h
    return 0.0


@njit(cache=True)
def next_level(sw, h, slot, level, err, lam_max, rate, t_now, cfg):
    """The fixed step: (level 0, dt_max [s])."""
    return 0, cfg.dt_max


@njit(cache=True)
def contact_placed(sw, k, st, p):
    """Nothing: no plate contacts."""
    return


@njit(cache=True)
def contacts_moved(sw, t, st, p, cfg):
    """Nothing: no plate contacts."""
    return

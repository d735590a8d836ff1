"""The compiled loop of a ramped settling of spheres (docs/model.md section 3.14, "Ramped
settling"): velocity Verlet of spheres in a box of plane walls under gravity, Hertz's
normal law with eq. (3)'s damping and Mindlin's tangential law (physics.mindlin), every
contact's stiffness scaled by a factor s (the Hertz coefficient A and Mindlin's 8 G* by s,
the damping coefficient c = alpha_n sqrt(m* A) by sqrt(s)) that the driver ramps from a
soft start to the real law's s = 1, and Cundall's local damping of the granules in contact
(YADE's NewtonIntegrator damping): each component of a granule's unbalanced force and
torque F reduced by lambda |F| where it does work (F v > 0) and raised by it where it
brakes, which leaves a state at rest, F = 0, unchanged.

Histories: per listed pair and per (granule, wall) the tangential spring's force per unit
stiffness factor, s xi [m] (so that a change of s leaves the tangential force where it was,
as a modulus raised at a fixed stress), and the contact radius of the last step. Arrays in,
arrays out; nothing allocated per step.
"""

from __future__ import annotations

import math
import os

# OpenMP's idle threads spin briefly before they sleep (as solver.blocks sets it, read when
# the threading layer loads; a user's own setting is kept).
os.environ.setdefault("GOMP_SPINCOUNT", "30000")

import numpy as np  # noqa: E402
from numba import prange  # noqa: E402
from granplate.jit import njit  # noqa: E402

from granplate.physics.contact import COEF_A, COEF_C, COEF_KT, COEF_MUT, COEF_XT, normal_force
from granplate.physics.mindlin import contact_radius, mindlin_force, rescale_history, rotate_history, tangential_damping
from granplate.physics.space import arm_torque_3d, normal_rate_3d, pair_contact_3d, slip_velocity_3d

#: Columns of a history row: s xi (3) [m], the contact radius a of the last step [m].
H_XI, H_A = 0, 3
N_HIST = 4
#: A granule's share of the rotational mobility in Verlet's stability bound: 1/m + r^2/I =
#: 3.5/m for a solid sphere (I = 2/5 m r^2).
ROLL_MOBILITY = 3.5


@njit(cache=True)
def _tangential(hist, p, c, s, sq, a, delta, nx, ny, nz, vsx, vsy, vsz, dt, n_abs):
    """Mindlin's force on the first body (eqs. M2-M5) at stiffness factor s (sq = sqrt(s)),
    the history row p of `hist` advanced over dt [s] by the slip v_s (dt = 0: the history's
    force, unchanged)."""
    k = s * c[COEF_KT] * a
    if k <= 0.0:
        return 0.0, 0.0, 0.0
    xx = hist[p, H_XI] / s
    xy = hist[p, H_XI + 1] / s
    xz = hist[p, H_XI + 2] / s
    xx, xy, xz = rescale_history(xx, xy, xz, a, hist[p, H_A])
    f_crit = c[COEF_MUT] * n_abs
    xx, xy, xz = rotate_history(xx, xy, xz, nx, ny, nz, k, f_crit)
    eta = sq * tangential_damping(c[COEF_XT], c[COEF_C], delta) if dt > 0.0 else 0.0
    fx, fy, fz, xx, xy, xz = mindlin_force(
        xx + dt * vsx, xy + dt * vsy, xz + dt * vsz, k, f_crit, -eta * vsx, -eta * vsy, -eta * vsz
    )
    hist[p, H_XI] = xx * s
    hist[p, H_XI + 1] = xy * s
    hist[p, H_XI + 2] = xz * s
    hist[p, H_A] = a
    return fx, fy, fz


@njit(cache=True)
def _push(f, tq, i, sign, n_abs, nx, ny, nz, arm, fx, fy, fz):
    """Granule i's share of a contact: the normal force -sign |N| n and sign F_t, and the
    torque arm n x F_t."""
    f[i, 0] += sign * (fx - n_abs * nx)
    f[i, 1] += sign * (fy - n_abs * ny)
    f[i, 2] += sign * (fz - n_abs * nz)
    tx, ty, tz = arm_torque_3d(arm, nx, ny, nz, fx, fy, fz)
    tq[i, 0] += tx
    tq[i, 1] += ty
    tq[i, 2] += tz


#: Columns of a pair's row of the pass's buffer: |N| [N], the unit normal n (3) [-], the
#: tangential force on the first granule (3) [N], the overlap delta [m] (<= 0: apart).
P_N, P_NX, P_FT, P_DELTA = 0, 1, 4, 7
N_PAIR = 8


@njit(refcount=True, cache=True)
def adjacency(pairs, n):
    """Each granule's listed pairs, ascending: the pair indices items[start[i]:start[i + 1]]
    of granule i (a counting sort of the pair list)."""
    start = np.zeros(n + 1, np.int64)
    for p in range(pairs.shape[0]):
        start[pairs[p, 0] + 1] += 1
        start[pairs[p, 1] + 1] += 1
    for i in range(n):
        start[i + 1] += start[i]
    fill = start[:-1].copy()
    items = np.empty(2 * pairs.shape[0], np.int64)
    for p in range(pairs.shape[0]):
        for q in range(2):
            i = pairs[p, q]
            items[fill[i]] = p
            fill[i] += 1
    return start, items


@njit(parallel=True)
def _pair_pass(x, v, w, radius, pairs, pcoef, phist, s, dt, elastic, buf):
    """Every listed pair's contact (a thread per block of pairs; each writes its own rows of
    buf and of the histories): |N|, n, Mindlin's force on the first granule, the overlap."""
    sq = math.sqrt(s)
    for p in prange(pairs.shape[0]):
        i = pairs[p, 0]
        j = pairs[p, 1]
        ri = radius[i]
        rj = radius[j]
        delta, nx, ny, nz = pair_contact_3d(x[i, 0], x[i, 1], x[i, 2], ri, x[j, 0], x[j, 1], x[j, 2], rj)
        buf[p, P_DELTA] = delta
        if delta <= 0.0:
            for k in range(N_HIST):
                phist[p, k] = 0.0
            continue
        c = pcoef[p]
        rate = normal_rate_3d(v[i, 0] - v[j, 0], v[i, 1] - v[j, 1], v[i, 2] - v[j, 2], nx, ny, nz)
        n_abs, n_el = normal_force(delta, rate, s * c[COEF_A], sq * c[COEF_C], True)
        if elastic:
            n_abs = n_el
        ai = ri - 0.5 * delta
        aj = rj - 0.5 * delta
        vsx, vsy, vsz = slip_velocity_3d(
            v[i, 0] - v[j, 0],
            v[i, 1] - v[j, 1],
            v[i, 2] - v[j, 2],
            ai * w[i, 0] + aj * w[j, 0],
            ai * w[i, 1] + aj * w[j, 1],
            ai * w[i, 2] + aj * w[j, 2],
            nx,
            ny,
            nz,
        )
        a = contact_radius(ri * rj / (ri + rj), delta)
        fx, fy, fz = _tangential(phist, p, c, s, sq, a, delta, nx, ny, nz, vsx, vsy, vsz, dt, n_abs)
        buf[p, P_N] = n_abs
        buf[p, P_NX] = nx
        buf[p, P_NX + 1] = ny
        buf[p, P_NX + 2] = nz
        buf[p, P_FT] = fx
        buf[p, P_FT + 1] = fy
        buf[p, P_FT + 2] = fz


@njit(parallel=True)
def _granule_pass(
    x, v, w, radius, mass, g, pairs, buf, start, items, walls, wcoef, whist, s, dt, elastic, f, tq, touch
):
    """Each granule's forces and torques (a thread per block of granules): its weight, its
    pairs' shares in ascending pair order (as a serial pass over the pair list adds them:
    the same sums, bit for bit, on any number of threads), then its wall contacts."""
    sq = math.sqrt(s)
    nw = walls.shape[0]
    for i in prange(x.shape[0]):
        for k in range(3):
            f[i, k] = mass[i] * g[k]
            tq[i, k] = 0.0
        touch[i] = 0
        ri = radius[i]
        for q in range(start[i], start[i + 1]):
            p = items[q]
            delta = buf[p, P_DELTA]
            if delta <= 0.0:
                continue
            sign = 1.0 if pairs[p, 0] == i else -1.0
            nx, ny, nz = buf[p, P_NX], buf[p, P_NX + 1], buf[p, P_NX + 2]
            _push(
                f,
                tq,
                i,
                sign,
                buf[p, P_N],
                nx,
                ny,
                nz,
                ri - 0.5 * delta,
                buf[p, P_FT],
                buf[p, P_FT + 1],
                buf[p, P_FT + 2],
            )
            touch[i] += 1
        for k in range(nw):
            nx, ny, nz = walls[k, 0], walls[k, 1], walls[k, 2]
            delta = x[i, 0] * nx + x[i, 1] * ny + x[i, 2] * nz + ri - walls[k, 3]
            row = i * nw + k
            if delta <= 0.0:
                for q in range(N_HIST):
                    whist[row, q] = 0.0
                continue
            c = wcoef[row]
            n_abs, n_el = normal_force(
                delta, normal_rate_3d(v[i, 0], v[i, 1], v[i, 2], nx, ny, nz), s * c[COEF_A], sq * c[COEF_C], True
            )
            if elastic:
                n_abs = n_el
            arm = ri - 0.5 * delta
            vsx, vsy, vsz = slip_velocity_3d(
                v[i, 0], v[i, 1], v[i, 2], arm * w[i, 0], arm * w[i, 1], arm * w[i, 2], nx, ny, nz
            )
            a = contact_radius(ri, delta)
            fx, fy, fz = _tangential(whist, row, c, s, sq, a, delta, nx, ny, nz, vsx, vsy, vsz, dt, n_abs)
            _push(f, tq, i, 1.0, n_abs, nx, ny, nz, arm, fx, fy, fz)
            touch[i] += 1


@njit(entry=True, cache=True)
def contact_forces(x, v, w, radius, mass, g, pairs, pcoef, phist, walls, wcoef, whist, s, dt, elastic, f, tq, touch):
    """Forces f (n, 3) [N] and torques tq (n, 3) [N m] on the granules at positions x, with
    gravity m g, the velocities v, spins w (the half step's) over the step dt [s] (the
    histories advance; dt = 0: the elastic state alone, histories kept), and touch (n,) the
    count of each granule's contacts. elastic: the normal force without eq. (3)'s damping
    (the static residual). walls (nw, 4): outward unit normal and offset of each plane."""
    start, items = adjacency(pairs, x.shape[0])
    buf = np.empty((pairs.shape[0], N_PAIR))
    _pair_pass(x, v, w, radius, pairs, pcoef, phist, s, dt, elastic, buf)
    _granule_pass(x, v, w, radius, mass, g, pairs, buf, start, items, walls, wcoef, whist, s, dt, elastic, f, tq, touch)


@njit(inline="always")
def _damped(fk, vk, lam):
    """Cundall's local damping of one component: fk reduced by lam |fk| where fk vk > 0,
    raised by it where fk vk < 0."""
    fv = fk * vk
    if fv > 0.0:
        return fk * (1.0 - lam)
    if fv < 0.0:
        return fk * (1.0 + lam)
    return fk


@njit(parallel=True)
def _drift(x, v, w, f, tq, mass, inertia, dt):
    """The first half kick and the drift of every granule."""
    for i in prange(x.shape[0]):
        hm = 0.5 * dt / mass[i]
        hi = 0.5 * dt / inertia[i]
        for k in range(3):
            v[i, k] += hm * f[i, k]
            w[i, k] += hi * tq[i, k]
            x[i, k] += dt * v[i, k]


@njit(refcount=True, parallel=True)
def _kick(x, v, w, f, tq, touch, mass, inertia, dt, lam, keep, spin_keep, x_ref, reach2):
    """Cundall's damping of the touching granules' forces and torques (in f, tq), the second
    half kick, the background damping; returns how many granules moved reach [m] or more."""
    far = 0
    for i in prange(x.shape[0]):
        hm = 0.5 * dt / mass[i]
        hi = 0.5 * dt / inertia[i]
        d2 = 0.0
        for k in range(3):
            if touch[i] != 0:
                f[i, k] = _damped(f[i, k], v[i, k], lam)
                tq[i, k] = _damped(tq[i, k], w[i, k], lam)
            v[i, k] = keep * (v[i, k] + hm * f[i, k])
            w[i, k] = spin_keep * (w[i, k] + hi * tq[i, k])
            d2 += (x[i, k] - x_ref[i, k]) ** 2
        if d2 >= reach2:
            far += 1
    return far


@njit(entry=True, cache=True)
def settle_steps(
    x,
    v,
    w,
    radius,
    mass,
    inertia,
    g,
    pairs,
    pcoef,
    phist,
    walls,
    wcoef,
    whist,
    s0,
    s1,
    lam,
    keep,
    spin_keep,
    dt,
    steps,
    x_ref,
    reach,
    f,
    tq,
    touch,
):
    """Up to `steps` velocity-Verlet steps of dt [s], the stiffness factor going
    geometrically from s0 to s1 over them, Cundall's damping lam [-], every spin multiplied
    by spin_keep [-] and every velocity by keep [-] once a step (a background damping: a
    granule held at two points or spinning about a contact's normal turns freely under both
    laws, a rattler bounces in its cage); stops early where a
    granule moved `reach` [m] or more from x_ref (its list is stale). f, tq, touch: the last
    pass's forces (kept across calls). Each pass runs on numba's threads (granules and pairs
    in blocks, every sum in a fixed order: the same state on any number of threads).
    Returns the steps done."""
    start, items = adjacency(pairs, x.shape[0])
    buf = np.empty((pairs.shape[0], N_PAIR))
    reach2 = reach * reach
    ratio = (s1 / s0) ** (1.0 / steps) if steps > 0 else 1.0
    s = s0
    for step in range(steps):
        s *= ratio
        _drift(x, v, w, f, tq, mass, inertia, dt)
        _pair_pass(x, v, w, radius, pairs, pcoef, phist, s, dt, False, buf)
        _granule_pass(
            x, v, w, radius, mass, g, pairs, buf, start, items, walls, wcoef, whist, s, dt, False, f, tq, touch
        )
        if _kick(x, v, w, f, tq, touch, mass, inertia, dt, lam, keep, spin_keep, x_ref, reach2) > 0:
            return step + 1
    return steps


@njit(entry=True, cache=True)
def stiffness_sums(x, radius, pairs, pcoef, walls, wcoef, s):
    """Each granule's sum of its contacts' normal stiffness dN/d delta = 3/2 s A delta^(1/2)
    and ROLL_MOBILITY x their tangential stiffness s 8 G* a [N/m] (Verlet's bound on the
    step: dt < sqrt(2 m / that sum))."""
    n = x.shape[0]
    out = np.zeros(n)
    for p in range(pairs.shape[0]):
        i = pairs[p, 0]
        j = pairs[p, 1]
        delta, _, _, _ = pair_contact_3d(x[i, 0], x[i, 1], x[i, 2], radius[i], x[j, 0], x[j, 1], x[j, 2], radius[j])
        if delta <= 0.0:
            continue
        a = contact_radius(radius[i] * radius[j] / (radius[i] + radius[j]), delta)
        k = s * (1.5 * pcoef[p, COEF_A] * math.sqrt(delta) + ROLL_MOBILITY * pcoef[p, COEF_KT] * a)
        out[i] += k
        out[j] += k
    nw = walls.shape[0]
    for i in range(n):
        for q in range(nw):
            delta = x[i, 0] * walls[q, 0] + x[i, 1] * walls[q, 1] + x[i, 2] * walls[q, 2] + radius[i] - walls[q, 3]
            if delta > 0.0:
                c = wcoef[i * nw + q]
                out[i] += s * (
                    1.5 * c[COEF_A] * math.sqrt(delta) + ROLL_MOBILITY * c[COEF_KT] * contact_radius(radius[i], delta)
                )
    return out


@njit(refcount=True, cache=True)
def wall_loads(x, radius, walls, wcoef, whist, s):
    """(nw, 4): each wall's elastic normal force [N] (positive in compression) and the
    tangential forces (3) [N] its contacts' histories exert on the granules, at rest."""
    nw = walls.shape[0]
    out = np.zeros((nw, 4))
    sq = math.sqrt(s)
    for i in range(x.shape[0]):
        for k in range(nw):
            nx, ny, nz = walls[k, 0], walls[k, 1], walls[k, 2]
            delta = x[i, 0] * nx + x[i, 1] * ny + x[i, 2] * nz + radius[i] - walls[k, 3]
            if delta <= 0.0:
                continue
            row = i * nw + k
            c = wcoef[row]
            n_abs = s * c[COEF_A] * delta * math.sqrt(delta)
            scratch = whist[row : row + 1].copy()
            fx, fy, fz = _tangential(
                scratch, 0, c, s, sq, contact_radius(radius[i], delta), delta, nx, ny, nz, 0.0, 0.0, 0.0, 0.0, n_abs
            )
            out[k, 0] += n_abs
            out[k, 1] += fx
            out[k, 2] += fy
            out[k, 3] += fz
    return out

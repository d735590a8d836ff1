"""Friction at an elastic body's contacts, split off as for granule pairs
(solver.friction_space.friction_flow; docs/model.md section 3.9): an exact impulse along the
slip, against the granule's and the body's mobility along it, booked as the kinetic energy
it removes.
"""

from __future__ import annotations

import math

from granplate.jit import njit

from granplate.model.inputs import GEO_DELTA, GEO_N, GEO_TOUCH
from granplate.physics.contact import COEF_MU, contact_arm
from granplate.physics.space import friction_along_slip
from granplate.solver.body_mindlin import contact_slip
from granplate.solver.body_surface import spread, surface_velocity
from granplate.solver.granular import friction_impulse
from granplate.solver.friction_space import apply_friction_impulse
from granplate.solver.granular3d import VX, WX


@njit(cache=True)
def slip_row(b, buf, i, sx, sy, sz, row) -> float:
    """row[m] = (Phi^T (w (x) s))_m, the modes' share of a unit impulse along s at granule
    i's contact point; returns row . row, the body's mobility along s [kg^-1]."""
    for m in range(row.shape[0]):
        row[m] = 0.0
    spread(b, buf, i, sx, sy, sz, row, 1.0)
    mob = 0.0
    for m in range(row.shape[0]):
        mob += row[m] * row[m]
    return mob


@njit(cache=True)
def friction_flow(y, qd, dt, b, buf, radius, mass, inertia, arm_shrink, forward) -> float:
    """Friction alone over dt [s] at every contact in touch on the body (buffer buf, |N|
    held), one after the other (forward or reversed): the exact impulse of
    solver.granular.friction_impulse along the slip s = v_s / |v_s| against the mobility
    1/m + a^2/I + |Phi^T (w (x) s)|^2, on the granule and, opposite, on the modes qd.
    Returns the energy dissipated [J]: the kinetic energy the impulses removed."""
    ng = y.shape[0]
    nm = qd.shape[0]
    row = b.mrow  # (nm,) scratch
    work = 0.0
    g = b.geo[buf]
    for kk in range(ng):
        i = kk if forward else ng - 1 - kk
        if g[i, GEO_TOUCH] == 0.0:
            continue
        c = b.coef[i]
        if c[COEF_MU] == 0.0 or g[i, GEO_N] <= 0.0:
            continue
        a = contact_arm(radius[i], g[i, GEO_DELTA], arm_shrink)
        v0, v1, v2 = surface_velocity(b, buf, i, qd)
        vsx, vsy, vsz, nx, ny, nz = contact_slip(y, g, i, a, v0, v1, v2)  # n from the granule into the body
        speed = math.sqrt(vsx * vsx + vsy * vsy + vsz * vsz)
        if speed == 0.0:
            continue
        sx = vsx / speed
        sy = vsy / speed
        sz = vsz / speed
        mob = slip_row(b, buf, i, sx, sy, sz, row)
        inv_m = 1.0 / mass[i]
        inv_i = 1.0 / inertia[i]
        imp, _ = friction_impulse(speed, g[i, GEO_N], c, inv_m + a * a * inv_i + mob, dt)
        if imp == 0.0:
            continue
        ke0 = 0.0
        for col in range(3):
            ke0 += 0.5 * mass[i] * y[i, VX + col] ** 2 + 0.5 * inertia[i] * y[i, WX + col] ** 2
        px, py, pz = friction_along_slip(imp, speed, vsx, vsy, vsz)
        apply_friction_impulse(y, i, a, inv_m, inv_i, nx, ny, nz, px, py, pz, 1.0)
        ke1 = 0.0
        for col in range(3):
            ke1 += 0.5 * mass[i] * y[i, VX + col] ** 2 + 0.5 * inertia[i] * y[i, WX + col] ** 2
        dke = ke1 - ke0
        for m in range(nm):  # the body gets -P = imp s
            dv = imp * row[m]
            dke += dv * (qd[m] + 0.5 * dv)
            qd[m] += dv
        work -= dke
    return work

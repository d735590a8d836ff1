"""The friction split off exactly per contact in space (docs/model.md sections 3.7 and
6.4): each pair and wall contact's slip speed relaxed along its own direction by an exact
impulse (as solver.granular.friction_flow in the plane), and that impulse applied to a
granule; solver.body_friction and solver.body_mindlin apply it at the elastic solid's
contacts too.
"""

from __future__ import annotations

from granplate.jit import njit

from granplate.model.inputs import HIST_MAX, HIST_RATE
from granplate.physics.contact import COEF_MU, contact_arm
from granplate.physics.laws import normal_law_force
from granplate.physics.space import arm_torque_3d, friction_along_slip, pair_contact_3d, wall_overlap_3d
from granplate.solver.drives import wall_motion
from granplate.solver.granular import friction_impulse
from granplate.solver.granular3d import VX, VY, VZ, WX, WY, WZ, X, Y, Z, _speed, pair_slip, wall_slip


@njit(cache=True)
def apply_friction_impulse(y, i, a, inv_m, inv_i, nx, ny, nz, px, py, pz, sign):
    """The impulse sign * P (px, py, pz the friction impulse on the first body [N s]) on
    granule i: its velocity by sign P / m, its spin by a n x P / I."""
    y[i, VX] += sign * px * inv_m
    y[i, VY] += sign * py * inv_m
    y[i, VZ] += sign * pz * inv_m
    tx, ty, tz = arm_torque_3d(a, nx, ny, nz, px, py, pz)
    y[i, WX] += tx * inv_i
    y[i, WY] += ty * inv_i
    y[i, WZ] += tz * inv_i


@njit(cache=True)
def friction_flow(y, dt, g, cfg, forward):
    """Friction alone at every pair and wall contact over dt [s], one contact after the
    other (as solver.granular.friction_flow): the slip speed |v_s| relaxes exactly along
    its own direction (a sphere's tangential mobility is isotropic, so an impulse along
    -v_s changes v_s along v_s only, at the rate m_t^-1 = 1/m_i + 1/m_j + a_i^2/I_i +
    a_j^2/I_j). Returns the energy dissipated [J]."""
    n_p = g.pair_ij.shape[0]
    n_w = g.wall_i.shape[0]
    half_shrink = 0.5 * cfg.arm_shrink
    work = 0.0
    for k in range(n_p + n_w):
        q = k if forward else n_p + n_w - 1 - k
        if q < n_p:
            c = g.pair_coef[q]
            if c[COEF_MU] == 0.0:
                continue
            i = g.pair_ij[q, 0]
            j = g.pair_ij[q, 1]
            ri = g.radius[i]
            rj = g.radius[j]
            delta, nx, ny, nz = pair_contact_3d(y[i, X], y[i, Y], y[i, Z], ri, y[j, X], y[j, Y], y[j, Z], rj)
            if delta <= 0.0:
                continue
            ai = contact_arm(ri, delta, half_shrink)
            aj = contact_arm(rj, delta, half_shrink)
            ddot, vsx, vsy, vsz = pair_slip(y, i, j, nx, ny, nz, ai, aj)
            speed = _speed(vsx, vsy, vsz)
            if speed == 0.0:
                continue
            n = normal_law_force(delta, ddot, c, g.pair_hist[q, HIST_MAX], g.pair_hist[q, HIST_RATE], cfg.clip)
            inv_mi = 1.0 / g.mass[i]
            inv_mj = 1.0 / g.mass[j]
            inv_ii = 1.0 / g.inertia[i]
            inv_ij = 1.0 / g.inertia[j]
            imp, dw = friction_impulse(speed, n, c, inv_mi + inv_mj + ai * ai * inv_ii + aj * aj * inv_ij, dt)
            px, py, pz = friction_along_slip(imp, speed, vsx, vsy, vsz)
            apply_friction_impulse(y, i, ai, inv_mi, inv_ii, nx, ny, nz, px, py, pz, 1.0)
            apply_friction_impulse(y, j, aj, inv_mj, inv_ij, nx, ny, nz, px, py, pz, -1.0)
            work += dw
        else:
            w = q - n_p
            i = g.wall_i[w]
            ri = g.radius[i]
            nx = g.wall_geo[w, 0]
            ny = g.wall_geo[w, 1]
            nz = g.wall_geo[w, 2]
            shift, vn, _ = wall_motion(g, w)  # (a driven wall where the last force pass put it)
            delta = wall_overlap_3d(y[i, X], y[i, Y], y[i, Z], ri, nx, ny, nz, g.wall_geo[w, 3] + shift)
            c = g.wall_coef[w]
            if delta <= 0.0 or c[COEF_MU] == 0.0:
                continue
            a = contact_arm(ri, delta, cfg.arm_shrink)
            ddot, vsx, vsy, vsz = wall_slip(y, i, nx, ny, nz, a)
            speed = _speed(vsx, vsy, vsz)
            if speed == 0.0:
                continue
            n = normal_law_force(delta, ddot - vn, c, g.wall_hist[w, HIST_MAX], g.wall_hist[w, HIST_RATE], cfg.clip)
            inv_m = 1.0 / g.mass[i]
            inv_i = 1.0 / g.inertia[i]
            imp, dw = friction_impulse(speed, n, c, inv_m + a * a * inv_i, dt)
            px, py, pz = friction_along_slip(imp, speed, vsx, vsy, vsz)
            apply_friction_impulse(y, i, a, inv_m, inv_i, nx, ny, nz, px, py, pz, 1.0)
            work += dw
    return work

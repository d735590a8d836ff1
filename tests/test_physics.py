"""The compiled contact laws and the energy residual against plain NumPy written from the
paper's equations (2)-(6), (8), (9) and (11), independently of the compiled code."""

from __future__ import annotations

import math

import numpy as np
import pytest

from granplate.physics import contact as C
from granplate.physics.energy import energy_residual, energy_total

RNG = np.random.default_rng(7)


def numpy_normal_force(delta, ddot, a, c):
    """Eq. (2): |N| = A delta^1.5 + alpha sqrt(m* A) delta^0.25 d(delta)/dt, >= 0."""
    return np.maximum(a * delta**1.5 + c * delta**0.25 * ddot, 0.0)


def test_normal_force_and_energy_eqs_2_9():
    """normal_force and contact_energy equal eq. (2) (clipped) and 2/5 A delta^2.5 (eq. 9)."""
    for _ in range(50):
        delta, ddot = RNG.uniform(1e-8, 1e-5), RNG.normal(0, 0.5)
        a, c = RNG.uniform(1e9, 1e11), RNG.uniform(0, 1e3)
        n, el = C.normal_force(delta, ddot, a, c, True)
        assert n == pytest.approx(numpy_normal_force(delta, ddot, a, c), rel=1e-13, abs=1e-12)
        assert el == pytest.approx(a * delta**1.5, rel=1e-13)
        assert C.contact_energy(delta, a) == pytest.approx(0.4 * a * delta**2.5, rel=1e-13)


def test_normal_force_slopes_are_derivatives_of_eq_2():
    """normal_force_slopes = (d|N|/d delta, d|N|/d delta rate) of eq. (2), by central differences."""
    delta, ddot, a, c = 3e-6, 0.2, 5e10, 40.0
    nd, nv = C.normal_force_slopes(delta, a, c)
    eps = 1e-12
    fd_d = (numpy_normal_force(delta + eps, ddot, a, c) - numpy_normal_force(delta - eps, ddot, a, c)) / (2 * eps)
    fd_v = (numpy_normal_force(delta, ddot + 1e-6, a, c) - numpy_normal_force(delta, ddot - 1e-6, a, c)) / 2e-6
    assert nd == pytest.approx(fd_d - c * 0.25 * delta**-0.75 * ddot, rel=1e-5)  # the elastic part's slope
    assert nv == pytest.approx(fd_v, rel=1e-7)


def test_friction_and_its_slope_eqs_5_8():
    """friction_magnitude = mu |N| tanh(k_s v) (eq. 5); friction_slope = its d/dv, the slope
    criterion (8) multiplies: local_map_modulus = 1/2 slope h c_t."""
    for _ in range(20):
        n, mu, ks = RNG.uniform(0, 1e3), RNG.uniform(0, 1), RNG.uniform(10, 1e4)
        v = RNG.uniform(-3, 3) / ks
        f = lambda vv: mu * n * np.tanh(ks * vv)  # noqa: E731
        assert C.friction_magnitude(n, v, mu, ks) == pytest.approx(f(v), rel=1e-14, abs=1e-300)
        h = 1e-5 / ks
        slope = (f(v + h) - f(v - h)) / (2 * h)
        assert C.friction_slope(n, v, mu, ks) == pytest.approx(slope, rel=1e-8)
        dt, ct = 1e-7, 3.0
        assert C.local_map_modulus(C.friction_slope(n, v, mu, ks), dt, ct) == pytest.approx(
            0.5 * slope * dt * ct, rel=1e-8
        )


def test_pair_kinematics_eq_6():
    """pair_overlap / pair_rates: delta = R_i + R_j - |s_j - s_i|, its rate, and the slip rate
    of eq. (6) as the relative tangential velocity of the two contact points."""
    for _ in range(20):
        si, sj = RNG.normal(0, 1e-2, 2), RNG.normal(0, 1e-2, 2)
        ri, rj = 0.01, 0.006
        vi, vj, wi, wj = RNG.normal(0, 1, 2), RNG.normal(0, 1, 2), RNG.normal(0, 10), RNG.normal(0, 10)
        d = sj - si
        dist = np.linalg.norm(d)
        n = d / dist
        t = np.array([-n[1], n[0]])
        delta, nx, nz = C.pair_overlap(si[0], si[1], ri, sj[0], sj[1], rj)
        assert delta == pytest.approx(ri + rj - dist, abs=1e-15)
        np.testing.assert_allclose([nx, nz], n, rtol=1e-14)
        ddot, vt = C.pair_rates(vi[0], vi[1], wi, vj[0], vj[1], wj, nx, nz, ri, rj)
        # contact point velocities: v + omega x r (2D: omega x r = omega (-r_y, r_x))
        cross = lambda w, r: w * np.array([-r[1], r[0]])  # noqa: E731
        vpi = vi + cross(wi, ri * n)
        vpj = vj + cross(wj, -rj * n)
        assert ddot == pytest.approx(-np.dot(vj - vi, n), rel=1e-12, abs=1e-14)
        assert vt == pytest.approx(np.dot(vpi - vpj, t), rel=1e-12, abs=1e-14)


def test_wall_and_plate_kinematics_eq_6():
    """Against a fixed wall and the moving plate edge: overlap, its rate and slip rate (eq. 6)."""
    x, y, r, vx, vy, w = 0.02, 0.011, 0.012, 0.3, -0.2, 5.0
    nrm = np.array([0.6, -0.8])
    assert C.wall_overlap(x, y, r, nrm[0], nrm[1], 0.001) == pytest.approx(np.dot([x, y], nrm) + r - 0.001)
    ddot, vt = C.wall_rates(vx, vy, w, nrm[0], nrm[1], r)
    t = np.array([-nrm[1], nrm[0]])
    assert ddot == pytest.approx(np.dot([vx, vy], nrm))
    assert vt == pytest.approx(np.dot(np.array([vx, vy]) + w * r * np.array([-nrm[1], nrm[0]]) * 1.0, t))
    assert C.plate_overlap(x, r, 0.031) == pytest.approx(x + r - 0.031)
    ddot, vt = C.plate_rates(vx, vy, w, r, 0.1, 0.05)
    assert (ddot, vt) == pytest.approx((vx - 0.1, vy - 0.05 + r * w))


def test_energy_residual_eq_11():
    """(E_g + E_p + D_visc + D_fric + D_plastic - E_in) / scale, eq. (11)."""
    tot = energy_total(1.0, 2.0, 0.25, 0.5, 0.0)
    assert tot == 3.75
    assert energy_total(1.0, 2.0, 0.25, 0.5, 0.125) == 3.875
    assert energy_residual(tot, 3.5, 4.0) == pytest.approx(0.0625)


def test_coefficient_columns():
    """The named columns index A, c, the normal and tangential law ids, mu, k_s, delta_y, then
    the law "johnson"'s R* Y, C, 1 / (L rate_ref), h, kappa, x_h, then Mindlin's 8 G*, mu and
    x_t, in that order (the model arrays' layout): what every force pass reads of every
    listed contact (A, c, the ids, mu) lies in a row's first 64 bytes, the normal law's own
    columns are one slice."""
    assert (C.COEF_A, C.COEF_C, C.COEF_NLAW, C.COEF_TLAW, C.COEF_MU, C.N_COEF) == (0, 1, 2, 3, 4, 16)
    assert max(C.COEF_A, C.COEF_C, C.COEF_NLAW, C.COEF_TLAW, C.COEF_MU) * 8 < 64
    assert (C.COEF_KS, C.COEF_DY) == (5, 6)
    assert (C.COEF_SY, C.COEF_RC, C.COEF_RL, C.COEF_H, C.COEF_KAPPA, C.COEF_XH) == (7, 8, 9, 10, 11, 12)
    assert (C.COEF_KT, C.COEF_MUT, C.COEF_XT) == (13, 14, 15)
    assert C.hertz_coefficient(1e11, 0.004) == pytest.approx(4 / 3 * 1e11 * math.sqrt(0.004))

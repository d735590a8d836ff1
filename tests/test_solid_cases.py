"""The 3D solid's verification cases: their pieces against exact results."""

from __future__ import annotations

import numpy as np
import pytest

from granplate.verification import solid_cases as S


def test_richardson_recovers_the_limit_and_order_of_an_exact_sequence():
    """Values L + C h^p on meshes halved in turn give back L and p exactly."""
    h = np.array([1.0, 0.5, 0.25])
    limit, order = S.richardson(3.0 + 0.7 * h**2.5)
    assert limit == pytest.approx(3.0, rel=1e-12) and order == pytest.approx(2.5, rel=1e-12)


def test_modes_plus_residual_compliance_are_the_static_solution():
    """On a small clamped plate the top face's deflection from the kept modes plus the
    residual compliance equals one sparse solve K u = f, and the pressure's consistent
    loads on the free dofs are at most the total q a^2 (the clamped edges take the rest)."""
    model = S.clamped_plate(4, 1, S.THIN)
    f_s = S.top_pressure_loads(model, S.PRESSURE)
    assert 0.0 < -f_s.sum() <= S.PRESSURE * S.SIDE**2 * (1 + 1e-12)
    u, direct = S.static_top(model, f_s), S.direct_static_top(model, f_s)
    assert np.max(np.abs(u - direct)) <= 1e-9 * np.max(np.abs(direct))
    assert S.centre_index(model) == int(np.argmax(np.abs(direct)))


def test_coarse_clamped_plate_is_near_leissa():
    """A 6 x 6 x 1 hex20 plate's first frequency parameter lies within 10% above the
    clamped Kirchhoff square's 35.99 (Leissa): a coarse mesh is stiffer, never softer."""
    from granplate.verification.plate_theory import LEISSA_CCCC_SQUARE

    lam = S.frequency_parameters(S.clamped_plate(6, 1, S.THIN), S.THIN, count=1)[0]
    assert LEISSA_CCCC_SQUARE[0] < lam < 1.1 * LEISSA_CCCC_SQUARE[0]


# --------------------------------------------------------------------------- impacts


def test_hunter_fraction_is_its_closed_form():
    """Hunter's radiated share 1.04 (v0 / c0)^(3/5): 1.04 at v0 = c0, and v0^(3/5) scaling."""
    from granplate.verification.impact_theory import hunter_radiated_fraction

    c0 = (2e11 / 7850.0) ** 0.5
    assert hunter_radiated_fraction(c0, 2e11, 7850.0) == pytest.approx(1.04, rel=1e-12)
    ratio = hunter_radiated_fraction(2.0, 2e11, 7850.0) / hunter_radiated_fraction(1.0, 2e11, 7850.0)
    assert ratio == pytest.approx(2.0**0.6, rel=1e-12)


def test_zener_at_zero_inelasticity_in_si_units_is_hertz():
    """Zener's model at lambda = 0 in the units of zener_scales is Hertz's rigid impact:
    t_c = 2.9432 delta_max / v0 and F_max = k delta_max^(3/2) (Johnson 1985, 11.4)."""
    from granplate.verification import impact_theory as T

    m, v, R = S.sphere_mass(0.002), 1.0, 0.002
    es = S.steel_pair_modulus()
    t_unit, f_unit = T.zener_scales(m, v, T.hertz_stiffness(es, R))
    z = T.zener_impact(0.0)
    assert z.contact_time * t_unit == pytest.approx(T.hertz_contact_time(m, v, es, R), rel=1e-7)
    assert z.peak_force * f_unit == pytest.approx(T.hertz_peak_force(m, v, es, R), rel=1e-7)


def test_first_contact_recovers_the_ends_of_a_sampled_pulse():
    """A force k d^(3/2) with d = A sin(pi (t - t0) / T), sampled every T/100 off the ends:
    the contact window comes back as (t0, t0 + T) to within 1e-5 T (d is linear at both ends)."""
    k, A, t0, T = 6.5e9, 4.8e-6, 1.234e-7, 1.4e-5
    t = np.arange(0.0, 2e-5, T / 100) + 0.37 * T / 100
    d = np.where((t > t0) & (t < t0 + T), A * np.sin(np.pi * (t - t0) / T), 0.0)
    start, end, last = S.first_contact(t, k * d**1.5, k)
    assert start == pytest.approx(t0, abs=1e-5 * T) and end == pytest.approx(t0 + T, abs=1e-5 * T)
    assert t[last] < t0 + T < t[last + 1]


def test_small_block_impact_conserves_energy_and_is_near_hertz():
    """The truncated-modes block (modes below 200 kHz + residual compliance): the energy
    balance holds to solver.energy_tol at every step, the sphere leaves at 1 m/s within
    0.1% (an elastic contact, the block's modes barely excited) and t_c lies within 5%
    above Hertz's on a half-space (the FE's point-load compliance adds, never removes)."""
    from granplate.setup.scenario import Solver
    from granplate.verification import impact_theory as T

    r = S.truncation_run(2e5)
    assert r["residual"] <= Solver().energy_tol
    assert r["restitution"] == pytest.approx(1.0, abs=1e-3)
    m, R = S.sphere_mass(S.TRUNCATION_RADIUS), S.TRUNCATION_RADIUS
    es = S.steel_pair_modulus()
    t_c = S.first_contact(np.array(r["t"]), np.array(r["force"]), T.hertz_stiffness(es, R))
    ratio = (t_c[1] - t_c[0]) / T.hertz_contact_time(m, 1.0, es, R)
    assert 1.0 < ratio < 1.05

"""The elastic-plastic normal law (granplate.physics.plastic, docs/model.md section 3.6)
against Thornton's equations written here in his own variables (E*, R*, p_y), against
Hertz, and against the work done along load paths (numerical quadrature)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

from granplate.physics import plastic as P
from granplate.physics.contact import hertz_coefficient

#: a steel-steel pair of 10 mm spheres: E* [Pa], R* [m], Y [Pa] (S355)
E_STAR = 200e9 / (2.0 * (1.0 - 0.3**2))
R_STAR = 0.005
P_Y = 1.6 * 355e6
A = 4.0 / 3.0 * E_STAR * math.sqrt(R_STAR)


def thornton(delta_max: float) -> dict:
    """Thornton (1997) in his variables: delta_y, F_y, the loading force, R_p, delta_p."""
    d_y = (math.pi * P_Y / (2.0 * E_STAR)) ** 2 * R_STAR
    f_y = math.pi**3 * P_Y**3 * R_STAR**2 / (6.0 * E_STAR**2)
    f_max = f_y + math.pi * P_Y * R_STAR * (delta_max - d_y)
    r_p = 4.0 * E_STAR / (3.0 * f_max) * ((2.0 * f_max + f_y) / (2.0 * math.pi * P_Y)) ** 1.5
    d_p = delta_max - (3.0 * f_max / (4.0 * E_STAR * math.sqrt(r_p))) ** (2.0 / 3.0)
    return {"delta_y": d_y, "F_y": f_y, "F_max": f_max, "R_p": r_p, "delta_p": d_p}


D_Y = P.yield_overlap(E_STAR, R_STAR, P_Y)


def test_yield_overlap_and_force_are_thorntons():
    """delta_y = (pi p_y / 2E*)^2 R* and F_y = pi^3 p_y^3 R*^2 / (6 E*^2) (Thornton 1997),
    and p0 (Hertz) equals p_y there: the onset ratio is 1."""
    ref = thornton(2.0 * D_Y)
    assert P.yield_overlap(E_STAR, R_STAR, P_Y) == pytest.approx(ref["delta_y"], rel=1e-14)
    assert P.yield_force(A, D_Y) == pytest.approx(ref["F_y"], rel=1e-13)
    assert P.hertz_peak_pressure(E_STAR, R_STAR, D_Y) == pytest.approx(P_Y, rel=1e-14)
    assert P.yield_onset_ratio(E_STAR, R_STAR, D_Y, 355e6) == pytest.approx(1.0, rel=1e-14)
    assert P.limiting_pressure(355e6) == pytest.approx(P_Y, rel=1e-15)


@pytest.mark.parametrize("ratio", [1.0001, 1.5, 4.0, 30.0, 1e4])
def test_unloading_curve_is_thorntons(ratio):
    """R_p = 4E*/(3F_max) ((2F_max + F_y)/(2 pi p_y))^(3/2) and the residual overlap
    delta_p of the Hertz curve of radius R_p through (delta_max, F_max) (Thornton 1997)."""
    m = ratio * D_Y
    ref = thornton(m)
    assert P.loading_force(A, D_Y, m) == pytest.approx(ref["F_max"], rel=1e-12)
    assert P.unloading_radius(R_STAR, A, D_Y, m) == pytest.approx(ref["R_p"], rel=1e-11)
    assert P.residual_overlap(D_Y, m) == pytest.approx(ref["delta_p"], rel=1e-9, abs=1e-12 * m)
    # half way down the unloading curve: Hertz of radius R_p from delta_p
    d = 0.5 * (m + ref["delta_p"])
    want = 4.0 / 3.0 * E_STAR * math.sqrt(ref["R_p"]) * (d - ref["delta_p"]) ** 1.5
    assert P.plastic_force(A, D_Y, d, m) == pytest.approx(want, rel=1e-9)


def test_contact_yield_overlap_of_materials():
    """delta_y of a contact from the softer body's Y: Thornton's delta_y for a known Y
    (steel on PTFE: PTFE's), inf (Hertz) for an unknown one."""
    from granplate.setup.materials import LIBRARY, Material, effective_modulus, softer_yield_strength

    steel, ptfe = LIBRARY["steel"], LIBRARY["ptfe"]
    e_star = effective_modulus(steel, ptfe)
    y = softer_yield_strength(steel, ptfe)
    assert y == ptfe.Y and softer_yield_strength(steel, None) == steel.Y
    want = (math.pi * 1.6 * ptfe.Y / (2.0 * e_star)) ** 2 * R_STAR
    assert P.contact_yield_overlap(e_star, R_STAR, y) == pytest.approx(want, rel=1e-14)
    glass = Material("glass", 63e9, 0.23, 2500.0)
    assert softer_yield_strength(steel, glass) is None
    assert P.contact_yield_overlap(e_star, R_STAR, None) == math.inf
    assert P.contact_yield_overlap(e_star, R_STAR, math.inf) == math.inf


def test_infinite_yield_strength_is_hertz():
    """Y -> infinity (delta_y above every overlap, or inf) gives Hertz's A delta^(3/2) and
    2/5 A delta^(5/2) to round-off (bitwise for delta_y = inf), with no plastic work."""
    a = hertz_coefficient(E_STAR, R_STAR)
    deltas = np.linspace(0.0, 1e-4, 101)
    big = P.yield_overlap(E_STAR, R_STAR, 1.6 * 1e15)
    assert big > deltas[-1]
    for d in deltas:
        hertz = 4.0 / 3.0 * E_STAR * math.sqrt(R_STAR) * d**1.5
        for d_y in (big, math.inf):
            for hist in (0.0, 0.5 * d, 1e-4):
                assert P.plastic_force(a, d_y, d, hist) == pytest.approx(hertz, rel=1e-14, abs=0.0)
                assert P.plastic_elastic_energy(a, d_y, d, hist) == pytest.approx(0.4 * hertz * d, rel=1e-14, abs=0.0)
                assert P.plastic_work(a, d_y, max(d, hist)) == 0.0
        assert P.plastic_force(a, math.inf, d, 1e-4) == a * d * math.sqrt(d)  # bitwise


def test_force_continuous_at_yield_and_at_largest_overlap():
    """The force and its slope are continuous at delta_y on loading, and unloading starts
    from the loading force at delta_max (no jump)."""
    eps = 1e-9
    below = P.plastic_force(A, D_Y, D_Y * (1 - eps), 0.0)
    above = P.plastic_force(A, D_Y, D_Y * (1 + eps), 0.0)
    f_y = thornton(D_Y)["F_y"]
    assert below == pytest.approx(f_y, rel=3e-9) and above == pytest.approx(f_y, rel=3e-9)
    assert P.plastic_force_slope(A, D_Y, D_Y * (1 - eps), 0.0) == pytest.approx(
        P.plastic_force_slope(A, D_Y, D_Y * (1 + eps), 0.0), rel=1e-8
    )
    for ratio in (1.2, 7.0, 300.0):
        m = ratio * D_Y
        f_max = thornton(m)["F_max"]
        assert P.plastic_force(A, D_Y, m * (1 - 1e-12), m) == pytest.approx(f_max, rel=1e-10)
        assert P.plastic_force(A, D_Y, m, m) == pytest.approx(f_max, rel=1e-12)
        assert P.plastic_elastic_energy(A, D_Y, m * (1 - 1e-12), m) == pytest.approx(
            P.plastic_elastic_energy(A, D_Y, m, m), rel=1e-10
        )


def fd(f, x: float, h: float) -> float:
    """Central difference (f(x + h) - f(x - h)) / 2h."""
    return (f(x + h) - f(x - h)) / (2.0 * h)


@pytest.mark.parametrize("ratio", [0.5, 1.3, 10.0, 200.0])
def test_force_is_the_derivative_of_stored_energy_below_the_largest_overlap(ratio):
    """On unloading and reloading (delta < delta_max) F = dU/d delta, central differences."""
    m = ratio * D_Y
    d_p = P.residual_overlap(D_Y, m)
    for s in (0.1, 0.5, 0.9):
        d = d_p + s * (m - d_p)
        h = 1e-5 * (m - d_p)
        num = fd(lambda x: P.plastic_elastic_energy(A, D_Y, x, m), d, h)
        assert P.plastic_force(A, D_Y, d, m) == pytest.approx(num, rel=1e-7)


@pytest.mark.parametrize("ratio", [0.5, 1.3, 10.0, 200.0])
def test_slope_matches_finite_differences(ratio):
    """dF/d delta of the law against central differences of the force on every branch:
    Hertz, loading line, unloading/reloading curve, open (below delta_p)."""
    m = ratio * D_Y
    d_p = P.residual_overlap(D_Y, m)
    points = [d_p + s * (m - d_p) for s in (0.2, 0.7)] + [1.5 * m] + ([0.5 * d_p] if d_p > 0 else [])
    for d in points:
        h = 1e-6 * m
        if d >= m:  # on the loading curve the history follows delta
            num = fd(lambda x: P.plastic_force(A, D_Y, x, x), d, h)
        else:
            num = fd(lambda x: P.plastic_force(A, D_Y, x, m), d, h)
        got = P.plastic_force_slope(A, D_Y, d, m)
        assert got == pytest.approx(num, rel=1e-6, abs=1e-9 * P.plastic_stiffness(A, D_Y))
        force, slope = P.plastic_response(A, D_Y, d, m)  # the one-call form: the same values
        assert force == pytest.approx(P.plastic_force(A, D_Y, d, m), rel=1e-14, abs=0.0)
        assert slope == pytest.approx(got, rel=1e-14, abs=0.0)


@pytest.mark.parametrize("ratio", [1.01, 2.0, 25.0, 1000.0])
def test_load_unload_loop_area_is_the_plastic_work(ratio):
    """The area of a load (0 -> delta_max) - unload (delta_max -> delta_p) loop, by
    quadrature of F d delta, equals W_p(delta_max), and the unloading returns all the
    stored energy: the work of unloading is U(delta_max)."""
    m = ratio * D_Y
    d_p = P.residual_overlap(D_Y, m)
    load = sum(
        quad(lambda x: P.plastic_force(A, D_Y, x, x), lo, hi, epsabs=0, epsrel=1e-13)[0]
        for lo, hi in ((0.0, min(D_Y, m)), (min(D_Y, m), m))
    )
    unload = quad(lambda x: P.plastic_force(A, D_Y, x, m), d_p, m, epsabs=0, epsrel=1e-13)[0]
    assert unload == pytest.approx(P.plastic_elastic_energy(A, D_Y, m, m), rel=1e-10)
    assert load - unload == pytest.approx(P.plastic_work(A, D_Y, m), rel=1e-8)


def test_stored_energy_plus_plastic_work_is_the_work_done_along_any_path():
    """Along a seeded random path of loading, unloading and reloading excursions, the work
    of the force (quadrature, segment by segment, the history updated as it goes) equals
    U(delta, delta_max) + W_p(delta_max) at every turning point."""
    rng = np.random.default_rng(7)
    path = np.concatenate([[0.0], np.cumsum(rng.uniform(-4.0, 6.0, 40)) * D_Y])
    path = np.maximum(path, 0.0)
    work, hist = 0.0, 0.0
    for lo, hi in zip(path[:-1], path[1:]):
        # a segment: below the history the curve is fixed; above it the loading curve
        knots = sorted({lo, hi, *[x for x in (hist, D_Y) if min(lo, hi) < x < max(lo, hi)]})
        sign = 1.0 if hi >= lo else -1.0
        for a, b in zip(knots[:-1], knots[1:]):
            seg = quad(lambda x: P.plastic_force(A, D_Y, x, hist), a, b, epsabs=0, epsrel=1e-12)[0]
            work += sign * seg
            if hi > lo:
                hist = max(hist, b)
        hist = max(hist, hi)
        want = P.plastic_elastic_energy(A, D_Y, hi, hist) + P.plastic_work(A, D_Y, hist)
        assert work == pytest.approx(want, rel=1e-9, abs=1e-12 * P.yield_force(A, D_Y) * D_Y)
    assert hist > 10.0 * D_Y  # the path went well past yield


def test_plastic_work_grows_and_history_updates():
    """W_p is zero up to delta_y and grows with delta_max; the history keeps the largest overlap."""
    ms = np.linspace(0.0, 50.0, 501) * D_Y
    w = np.array([P.plastic_work(A, D_Y, m) for m in ms])
    assert np.all(w[ms <= D_Y] == 0.0) and np.all(np.diff(w[ms > D_Y]) > 0.0)
    assert P.updated_max_overlap(2.0, 1.0) == 2.0 and P.updated_max_overlap(0.5, 1.0) == 1.0

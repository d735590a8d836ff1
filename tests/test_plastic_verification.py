"""Head-on impacts with Thornton's elastic-plastic law (granplate.verification.plastic):
the independent integration against Thornton's and Johnson's closed forms, and against
the plastic work of granplate.physics.plastic."""

from __future__ import annotations

import math

import numpy as np
import pytest

from granplate.physics import plastic as P
from granplate.physics.contact import hertz_coefficient
from granplate.setup.materials import LIBRARY, effective_modulus, softer_yield_strength, sphere_mass
from granplate.verification import plastic as V

STEEL, PTFE = LIBRARY["steel"], LIBRARY["ptfe"]


def pair(a, b, r_a: float, r_b: float | None) -> tuple[float, float, float, float, float]:
    """(m1, m2, E*, R*, p_y) of sphere a on sphere b (r_b None: a rigid wall)."""
    m1 = sphere_mass(r_a, a.rho)
    if r_b is None:
        return m1, math.inf, effective_modulus(a, None), r_a, 1.6 * softer_yield_strength(a, None)
    return (
        m1,
        sphere_mass(r_b, b.rho),
        effective_modulus(a, b),
        r_a * r_b / (r_a + r_b),
        1.6 * softer_yield_strength(a, b),
    )


CASES = {
    "steel-steel spheres": pair(STEEL, STEEL, 0.01, 0.01),
    "steel on ptfe sphere": pair(STEEL, PTFE, 0.01, 0.005),
    "steel on a wall": pair(STEEL, None, 0.01, None),
}


def m_star(m1: float, m2: float) -> float:
    return m1 if math.isinf(m2) else m1 * m2 / (m1 + m2)


@pytest.mark.parametrize("name", sorted(CASES))
def test_yield_velocity_is_where_the_impact_starts_to_yield(name):
    """At v_y (P11) Hertz's largest overlap (15 m* v^2 / (16 E* sqrt R*))^(2/5) is delta_y,
    and the integrated impact stays elastic just below v_y and yields just above it."""
    m1, m2, e_star, r_star, p_y = CASES[name]
    v_y = V.thornton_yield_velocity(e_star, r_star, m_star(m1, m2), p_y)
    hertz_max = (15.0 * m_star(m1, m2) * v_y**2 / (16.0 * e_star * math.sqrt(r_star))) ** 0.4
    assert hertz_max == pytest.approx(V.yield_overlap(e_star, r_star, p_y), rel=1e-13)
    below = V.impact(m1, m2, e_star, r_star, p_y, 0.999 * v_y)
    above = V.impact(m1, m2, e_star, r_star, p_y, 1.001 * v_y)
    assert not below["plastic"] and below["e"] == pytest.approx(1.0, abs=1e-9)
    assert above["plastic"] and above["e"] < 1.0 and above["delta_p"] > 0.0


def test_johnsons_yield_velocity_of_a_sphere_on_a_flat():
    """Johnson's rho v_y^2 / Y = 26 (Y/E*)^4 agrees with P11 for a sphere on a rigid flat
    within 1% (26 rounds the exact pi^4 1.6^5 / 40 = 25.5: 0.9% in v_y)."""
    m1, _, e_star, r_star, p_y = CASES["steel on a wall"]
    thornton = V.thornton_yield_velocity(e_star, r_star, m1, p_y)
    johnson = V.johnson_yield_velocity(e_star, STEEL.rho, STEEL.Y)
    assert johnson == pytest.approx(thornton, rel=0.01)
    exact = math.pi**4 * 1.6**5 / 40.0
    assert STEEL.rho * thornton**2 / STEEL.Y == pytest.approx(exact * (STEEL.Y / e_star) ** 4, rel=1e-12)


@pytest.mark.parametrize("name", sorted(CASES))
def test_restitution_matches_thorntons_closed_form(name):
    """The integrated impact's e equals Thornton's e(v/v_y) (P12) within 1% (in fact to the
    integrator's tolerance) from 2 to 100 v_y; e falls monotonically and e(v_y) = 1."""
    m1, m2, e_star, r_star, p_y = CASES[name]
    v_y = V.thornton_yield_velocity(e_star, r_star, m_star(m1, m2), p_y)
    ratios = np.geomspace(2.0, 100.0, 9)
    es = []
    for r in ratios:
        got = V.impact(m1, m2, e_star, r_star, p_y, r * v_y)
        want = V.thornton_restitution(r)
        assert got["e"] == pytest.approx(want, rel=0.01)
        assert got["e"] == pytest.approx(want, rel=1e-8)
        assert got["kinetic_after"] == pytest.approx(got["e"] ** 2 * got["kinetic_before"], rel=1e-9)
        es.append(got["e"])
    assert np.all(np.diff(es) < 0.0) and V.thornton_restitution(1.0) == pytest.approx(1.0, rel=1e-15)


@pytest.mark.parametrize("ratio", [1.5, 10.0, 100.0])
def test_lost_kinetic_energy_is_the_plastic_work_of_the_law(ratio):
    """The kinetic energy an integrated impact loses is W_p(delta_max) of
    granplate.physics.plastic (P10), and the integration's delta_p and R_p are the law's."""
    m1, m2, e_star, r_star, p_y = CASES["steel on ptfe sphere"]
    v_y = V.thornton_yield_velocity(e_star, r_star, m_star(m1, m2), p_y)
    got = V.impact(m1, m2, e_star, r_star, p_y, ratio * v_y)
    a = hertz_coefficient(e_star, r_star)
    d_y = P.yield_overlap(e_star, r_star, p_y)
    lost = got["kinetic_before"] - got["kinetic_after"]
    assert lost == pytest.approx(P.plastic_work(a, d_y, got["delta_max"]), rel=1e-8)
    assert got["delta_p"] == pytest.approx(P.residual_overlap(d_y, got["delta_max"]), rel=1e-9)
    assert got["R_p"] == pytest.approx(P.unloading_radius(r_star, a, d_y, got["delta_max"]), rel=1e-10)

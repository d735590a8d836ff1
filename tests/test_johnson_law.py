"""The law "johnson" (docs/model.md section 3.10) against its closed forms: Hertz below
yield, force and slope continuous at yield and at the bridge's end, the fully plastic
line 2 pi R* h Y(rate) delta, unloading and reloading along the Hertz curve of the
residual overlap, energy (stored + plastic work = work done, by quadrature), the rate
dependence, the commit rule, and bad material fields refused by name."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

import granplate as gp
from granplate.errors import ScenarioError
from granplate.setup.validate import validate
from granplate.physics.cavity import (
    X_BRIDGE,
    fixing_speed,
    hardness_overlap,
    johnson_normal_response,
    johnson_state,
    loading_curve,
    rate_factor,
    unloading_span,
)
from granplate.physics.contact import COEF_A, COEF_C, COEF_DY, COEF_RL, hertz_elastic, normal_response
from granplate.physics.laws import normal_law_response
from granplate.verification.measured import johnson_row

ROW = johnson_row("steel_302")  # two spheres R = 3.175 mm of AISI 302
V = 3.0  # [m/s] the approach speed fixing the yield strength
PHI = 1.0 + 0.025 * math.log(V / (2 * 3.175e-3) / 1e-3)


def dy() -> float:
    return ROW[COEF_DY] * PHI * PHI


def force(d: float, m: float = 0.0) -> float:
    return johnson_state(d, m, ROW, PHI, 0.0)[0]


def test_elastic_below_yield_is_hertz_bitwise():
    """Below the yield overlap the law is Hertz's eq. (2), damping included, in the same operations."""
    row = ROW.copy()
    row[COEF_C] = 123.0
    for d in np.linspace(0.05, 0.99, 7) * dy():
        a = johnson_normal_response(d, 0.4, row, 0.9 * d, PHI, True)
        assert a[:3] == normal_response(d, 0.4, row[0], row[COEF_C], True) and a[3] == 0.0
        assert force(d) == hertz_elastic(d, row[0])


@pytest.mark.parametrize("x0", [1.0, X_BRIDGE])
def test_force_and_slope_continuous_at_yield_and_bridge(x0):
    """Force and slope agree to 1e-7 either side of x = 1 (yield: Hertz's slope 3/2 A delta_y^(1/2)) and X_BRIDGE."""
    d0 = x0 * dy()
    lo, hi = johnson_state(d0 * (1 - 1e-9), 0.0, ROW, PHI, 0.0), johnson_state(d0 * (1 + 1e-9), 0.0, ROW, PHI, 0.0)
    assert hi[0] == pytest.approx(lo[0], rel=1e-7)
    assert hi[1] == pytest.approx(lo[1], rel=1e-7)
    if x0 == 1.0:
        assert lo[1] == pytest.approx(1.5 * ROW[COEF_A] * math.sqrt(d0), rel=1e-7)


def test_fully_plastic_line_and_cavity_pressure():
    """Past the hardness overlap F = 2 pi R* h Y(rate) delta (pressure h Y over a^2 = 2 R* delta);
    below it, the mean pressure is Johnson's cavity (2/3) Y [1 + ln(E* a / (3 Y R*))]."""
    r_star, y, e_star = 3.175e-3 / 2, 600e6 * PHI, 200e9 / (2 * 0.91)
    d = 2.0 * hardness_overlap(2.8) * dy()
    assert force(d) == pytest.approx(2 * math.pi * r_star * 2.8 * y * d, rel=1e-12)
    d = 20.0 * dy()
    a = math.sqrt(2 * r_star * d)
    p_m = 2 / 3 * y * (1 + math.log(e_star * a / (3 * y * r_star)))
    assert force(d) == pytest.approx(math.pi * a * a * p_m, rel=1e-9)


def test_unloading_and_reloading_follow_the_residual_hertz_curve():
    """From delta_max: F = F_max ((delta - delta_p) / (delta_max - delta_p))^(3/2), zero at and below delta_p,
    back to F_max on reloading, then on along the loading curve."""
    m = 300.0 * dy()
    f_max, _, _, _, d_p = johnson_state(m, m, ROW, PHI, 0.0)
    assert 0.0 < d_p < m
    for s in (0.2, 0.5, 0.9):
        d = d_p + s * (m - d_p)
        assert force(d, m) == pytest.approx(f_max * s**1.5, rel=1e-12)
    assert force(d_p * 0.999, m) == 0.0
    assert force(m, m) == f_max and force(1.1 * m, m) == force(1.1 * m)


@pytest.mark.parametrize("h, kappa", [(2.8, 0.4), (1.5, 0.5), (4.0, 0.05)])
def test_energy_stored_plus_plastic_work_is_the_work_done(h, kappa):
    """Along loading to x_m then unloading: the work of the loading curve (quadrature) equals the
    stored energy at x_m plus W_p(x_m); the unloading returns the stored energy; W_p never decreases."""
    for xm in (1.5, 3.0, 30.0, 3000.0):
        f, k, w = loading_curve(xm, h)
        work = quad(
            lambda x: loading_curve(x, h)[0] if x >= 1.0 else loading_curve(1.0, h)[0] * x**1.5,
            0.0,
            xm,
            points=[p for p in (1.0, X_BRIDGE, hardness_overlap(h)) if p < xm],
            limit=200,
        )[0]
        assert w == pytest.approx(work, rel=1e-8)
        om = unloading_span(xm, f, kappa)
        back = quad(lambda x: f * ((x - (xm - om)) / om) ** 1.5, xm - om, xm)[0]
        assert back == pytest.approx(0.4 * f * om, rel=1e-9)
    xs = np.geomspace(1.0, 1e5, 3000)
    wp = [
        loading_curve(x, h)[2] - 0.4 * loading_curve(x, h)[0] * unloading_span(x, loading_curve(x, h)[0], kappa)
        for x in xs
    ]
    assert np.all(np.diff(wp) >= -1e-12 * np.abs(wp[1:]))


def test_response_books_the_plastic_work_past_the_largest_overlap():
    """normal_law_response's plastic work is W_p(delta) - W_p(delta_max) while loading, 0 below delta_max."""
    a, b = 40.0 * dy(), 55.0 * dy()
    wa, wb = johnson_state(a, a, ROW, PHI, 0.0)[3], johnson_state(b, b, ROW, PHI, 0.0)[3]
    assert normal_law_response(b, 1.0, ROW, a, PHI, True)[3] == pytest.approx(wb - wa, rel=1e-12)
    assert normal_law_response(a, -1.0, ROW, b, PHI, True)[3] == 0.0


def test_rate_dependence():
    """Y(rate) = Y [1 + C ln(rate / rate_ref)], rate = v / (2 R): the fully plastic force scales with it;
    1 at or below the reference rate; an unset rate factor takes the current approach speed's."""
    assert rate_factor(V, 0.025, ROW[COEF_RL]) == pytest.approx(PHI, rel=1e-14)
    assert rate_factor(1e-9, 0.025, ROW[COEF_RL]) == 1.0 and rate_factor(-1.0, 0.025, ROW[COEF_RL]) == 1.0
    d = 5e-4
    slow = johnson_state(d, 0.0, ROW, 1.0, 0.0)[0]
    assert johnson_state(d, 0.0, ROW, PHI, 0.0)[0] == pytest.approx(PHI * slow, rel=1e-12)
    assert johnson_state(d, 0.0, ROW, 0.0, V)[0] == johnson_state(d, 0.0, ROW, PHI, 0.0)[0]


def test_bridge_constants_hold_over_the_allowed_hardness_ratios():
    """The cubic bridge's constants assume the cap lies beyond X_BRIDGE: true for every allowed h."""
    from granplate.physics.cavity import H_BRIDGE, cavity_pressure
    from granplate.setup.validate import HARDNESS_RATIO_RANGE

    assert cavity_pressure(X_BRIDGE) == pytest.approx(H_BRIDGE) and H_BRIDGE < HARDNESS_RATIO_RANGE[0]


def test_commit_rule_fixes_the_loading_speed_of_the_step():
    """fixing_speed: the growth of the largest overlap over the step; -1 (rate-free) without a previous one."""
    assert fixing_speed(3e-6, 1e-6, 2e-6, 1e-6) == pytest.approx(2.0)
    assert fixing_speed(3e-6, 0.0, 2e-6, 0.0) == -1.0


MAT = "[materials.m]\nE = 2e11\nnu = 0.3\nrho = 7800\nY = 6e8\n"


@pytest.mark.parametrize(
    "extra, field",
    [
        ("C = 0.02\n", "materials.m.rate_ref"),
        ("rate_ref = 1e-3\n", "materials.m.C"),
        ("C = -0.1\nrate_ref = 1e-3\n", "materials.m.C"),
        ("C = 0.02\nrate_ref = 0\n", "materials.m.rate_ref"),
        ("hardness_ratio = 9\n", "materials.m.hardness_ratio"),
        ("unloading_factor = 0.75\n", "materials.m.unloading_factor"),
    ],
)
def test_bad_material_fields_are_refused_by_name(extra, field):
    text = (
        MAT
        + extra
        + (
            '[[granules]]\nlabel = "a"\nx = 0.0\ny = 0.0\nradius = 0.01\nmaterial = "m"\n'
            '[load]\nkind = "none"\n[contact]\nnormal_law = "johnson"\n'
        )
    )
    with pytest.raises(ScenarioError) as e:
        validate(gp.loads(text))
    assert e.value.field == field


def test_unknown_law_lists_johnson_and_johnson_needs_y():
    base = (
        '[[granules]]\nlabel = "a"\nx = 0.0\ny = 0.0\nradius = 0.01\nmaterial = "steel"\n'
        '[[granules]]\nlabel = "b"\nx = 0.03\ny = 0.0\nradius = 0.01\nmaterial = "m"\n[load]\nkind = "none"\n'
    )
    with pytest.raises(ScenarioError, match="johnson"):
        gp.loads(base + '[materials.m]\nE = 2e11\nnu = 0.3\nrho = 7800\n[contact]\nnormal_law = "jonson"\n')
    with pytest.raises(ScenarioError) as e:
        validate(gp.loads(base + '[materials.m]\nE = 2e11\nnu = 0.3\nrho = 7800\n[contact]\nnormal_law = "johnson"\n'))
    assert e.value.field == "contact.normal_law"


def test_built_in_materials_round_trip():
    """steel_440c, steel_302, aluminium_2017 carry the authors' table; a material's law fields survive TOML."""
    from granplate.setup.materials import LIBRARY

    assert (LIBRARY["steel_440c"].Y, LIBRARY["steel_302"].C, LIBRARY["aluminium_2017"].E) == (1896e6, 0.025, 76e9)
    s = gp.loads(
        MAT + "C = 0.02\nrate_ref = 0.001\nhardness_ratio = 3\nunloading_factor = 0.3\n"
        '[[granules]]\nlabel = "a"\nx = 0.0\ny = 0.0\nradius = 0.01\nmaterial = "m"\n[load]\nkind = "none"\n'
    )
    assert gp.loads(gp.dumps(s)).material("m") == s.material("m")

"""Mindlin friction on the whole oblique-impact curve (a sphere on a rigid floor, Psi2 against
Psi1, docs/model.md section 3.16) held against truth: the gross-sliding line Psi2 = Psi1 - 7
kappa and its threshold 7 kappa - 1/3 in closed form, the independent scipy integration of
the continuous law (stick and slip switched at located events) across the regimes,
converging with the step, and LAMMPS's `mindlin_rescale` at the same step."""

from __future__ import annotations

import pytest

from granplate.setup.materials import LIBRARY
from granplate.verification import lammps as L
from granplate.verification import oblique_mindlin_cases as C
from granplate.verification.oblique_mindlin import sliding_line, sliding_threshold, stiffness_ratio

NU = LIBRARY[C.MATERIAL].nu


def test_gross_sliding_takes_the_closed_form_line():
    """Above the threshold the rebound is the closed form: Psi2 = Psi1 - 7 kappa and R omega2
    = 5 mu v_n, in granplate (to 1e-7: the normal impulse's step error, measured 2e-9) and in
    the independent integration (to 1e-9)."""
    for psi1 in (6.0, 10.0):
        ours = C.granplate_impact(psi1)
        ref = C.reference_of(psi1)
        line = float(sliding_line(psi1, NU))
        assert abs(ours.psi2 - line) < 1e-7
        assert abs(ref.psi2 - line) < 1e-9
        assert C.RADIUS * ours.omega2 == pytest.approx(5.0 * C.MU * C.V_N, rel=1e-7)
    assert 7.0 * stiffness_ratio(NU) == pytest.approx(14.0 * (1.0 - NU) / (2.0 - NU), rel=1e-15)  # 4 chi


def test_sliding_threshold_is_where_the_contact_first_sticks():
    """The derived threshold 7 kappa - 1/3: just above it the integration of the law is on
    the line (Psi2 = -1/3 at the threshold); just below it a stick phase takes impulse off
    and Psi2 lies above the line."""
    top = sliding_threshold(NU)
    above = C.reference_of(top + 0.01)
    below = C.reference_of(top - 0.1)
    assert above.psi2 == pytest.approx(float(sliding_line(top + 0.01, NU)), abs=1e-9)
    assert below.psi2 - float(sliding_line(top - 0.1, NU)) > 1e-3
    assert float(sliding_line(top, NU)) == pytest.approx(-1.0 / 3.0, abs=1e-14)


@pytest.mark.parametrize("psi1", [0.3, 1.25, 2.5, 4.0, 7.0])
def test_rebound_agrees_with_the_independent_integration(psi1):
    """Across the regimes (sticking at touch, stick-slip with the reversal, gross sliding):
    granplate's Psi2 within 5e-4 and its rebound speeds (v_n2, v_t2, R omega2) within 1e-4 of
    v_n of the integration at 2 ns (measured at most 1.7e-4 and 4.3e-5)."""
    ours = C.granplate_impact(psi1)
    ref = C.reference_of(psi1)
    assert abs(ours.psi2 - ref.psi2) < 5e-4
    assert C.speed_difference(ours, ref) < 1e-4


def test_rebound_converges_to_the_integration_as_the_step_halves():
    """In the stick-slip range the error halves with the step (first order: the switch falls
    inside a step); the integration itself is converged (rtol 1e-12 against 1e-10: 1e-8)."""
    ref = C.reference_of(4.0)
    coarse = abs(C.granplate_impact(4.0).psi2 - ref.psi2)
    fine = abs(C.granplate_impact(4.0, C.STEP / 2).psi2 - ref.psi2)
    assert 1.8 < coarse / fine < 2.2
    mat = LIBRARY[C.MATERIAL]
    loose = C.reference_impact(C.V_N, C.tangential_speed(4.0, NU), C.RADIUS, mat.E, NU, mat.rho, C.MU, rtol=1e-10)
    assert abs(loose.psi2 - ref.psi2) < 1e-8


@pytest.mark.skipif(bool(L.unavailable()), reason=L.unavailable() or "lammps available")
@pytest.mark.parametrize("psi1", [0.5, 2.0, 6.0])
def test_rebound_agrees_with_lammps_at_the_same_step(psi1):
    """LAMMPS's fix wall/gran with hertz/material and tangential mindlin_rescale, velocity
    Verlet at the same step: the rebound speeds agree to 1e-6 of v_n (measured 5e-14)."""
    assert C.speed_difference(C.granplate_impact(psi1), C.lammps_impact(psi1)) < 1e-6


def test_the_normalised_curve_depends_on_nothing_but_poissons_ratio():
    """Hertz's and Mindlin's laws are self-similar: the integration's Psi2 at a given Psi1 is
    the same at ten times the normal speed and twice the density (to 1e-8), so the curve is
    one per nu, as Maw, Barber & Fawcett's."""
    mat = LIBRARY[C.MATERIAL]
    base = C.reference_of(2.5).psi2
    for v_n, rho in ((2.0, mat.rho), (C.V_N, 2.0 * mat.rho)):
        v_c1 = C.tangential_speed(2.5, NU, v_n=v_n)
        other = C.reference_impact(v_n, v_c1, C.RADIUS, mat.E, NU, rho, C.MU)
        assert abs(other.psi2 - base) < 1e-8


@pytest.mark.skipif(bool(L.unavailable()), reason=L.unavailable() or "lammps available")
def test_equal_spheres_agree_with_lammps_at_the_same_step():
    """Two equal spheres in stick-slip (Psi1 = 2.5) with LAMMPS's arms against pair granular
    hertz/material + mindlin_rescale: both spheres' speeds and R omega to 1e-6 of v_n."""
    assert C.pair_difference(C.pair_impact(2.5, "lammps"), C.lammps_pair(2.5)) < 1e-6

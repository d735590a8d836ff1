"""A ball dropped on a floor under gravity (verification case `gravity-bounce`): the
reference integration conserves energy without damping, the loop's free fall is the
parabola, its bounce apex is the reference's and eq. (11) holds with gravity's work."""

from __future__ import annotations

import pytest

from granplate.results.run import simulate
from granplate.verification import all_cases
from granplate.verification.gravity_cases import bounce_scenario, measured_bounce, reference_bounce
from granplate.verification.granular import impact_ode


def test_the_reference_bounces_elastically_without_damping():
    """Undamped Hertz contact with gravity conserves energy: the reference's rebound speed is its
    impact speed (to its integration tolerance), and with damping it is Hertz's e(alpha) up to
    gravity's effect during the contact (g t_c / v)."""
    s = bounce_scenario(drop=0.005)
    from granplate.setup.io import with_changes

    elastic = reference_bounce(with_changes(s, {"contact.alpha_n": 0.0}))
    assert elastic["e"] == pytest.approx(1.0, abs=1e-9)
    damped = reference_bounce(s)
    bound = 9.81 * damped["t_c"] / damped["v_in"]
    assert damped["e"] == pytest.approx(impact_ode(s.contact.alpha_n)[0], rel=bound)


def test_the_loop_falls_on_the_parabola_and_bounces_to_the_reference_apex():
    """Velocity Verlet under gravity: the free fall is the parabola to round-off, the apex after
    the bounce is the reference's within 1e-4 (h = 2e-7 s), eq. (11) holds to solver.energy_tol."""
    s = bounce_scenario(drop=0.005, step=2e-7)
    ds = simulate(s, progress=False)
    got, ref = measured_bounce(ds, s), reference_bounce(s)
    assert got["fall_error"] <= 1e-12
    assert got["apex"] == pytest.approx(ref["apex"], rel=1e-4)
    assert got["residual"] <= s.solver.energy_tol


def test_the_case_is_registered():
    """`granplate verify --case gravity-bounce` finds it."""
    assert "gravity-bounce" in [c.name for c in all_cases()]

"""The half-sine shock (docs/model.md section 5): resultants on granules and their sum."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad

from granplate.physics.shock import granule_resultants, time_profile, total_impulse


@pytest.mark.parametrize("yc", [0.03, 0.05, 0.07, 0.09, 0.01])
def test_resultants_against_quadrature(yc):
    """F = int q dy and tau = -int (y - yc) q dy over the granule's span, by quadrature."""
    R, y0, L = 0.01, 0.025, 0.05
    q = lambda y: np.sin(np.pi * (y - y0) / L) if y0 <= y <= y0 + L else 0.0
    a, b = yc - R, yc + R
    f_ref = quad(q, a, b, points=[y0, y0 + L])[0]
    t_ref = -quad(lambda y: (y - yc) * q(y), a, b, points=[y0, y0 + L])[0]
    f, t = granule_resultants(yc, R, y0, L)
    assert f == pytest.approx(f_ref, rel=1e-10, abs=1e-15)
    assert t == pytest.approx(t_ref, rel=1e-10, abs=1e-15)


def test_paper_load_distribution():
    """Only granules 2, 3, 4 are loaded; 3 takes a pure force, 2 and 4 opposite torques;
    the forces add up to the whole line load 2L/pi."""
    R, y0, L = 0.01, 0.025, 0.05
    res = {lab: granule_resultants(y, R, y0, L) for lab, y in zip("12345", (0.09, 0.07, 0.05, 0.03, 0.01))}
    assert res["1"] == (0.0, 0.0) and res["5"] == (0.0, 0.0)
    assert res["3"][1] == pytest.approx(0.0, abs=1e-15)
    assert res["2"][1] == pytest.approx(-res["4"][1], rel=1e-12)
    assert res["2"][1] > 0  # most of its load is below its centre: a +x push there turns it anticlockwise
    assert sum(f for f, _ in res.values()) == pytest.approx(2 * L / np.pi, rel=1e-12)


def test_time_profile_and_impulse():
    """sin(pi t/T) on [0, T], zero outside; the total impulse q0 (2L/pi)(2T/pi)."""
    T = 1e-5
    assert time_profile(-1e-9, T) == 0.0 and time_profile(T * 1.01, T) == 0.0
    assert time_profile(T / 2, T) == pytest.approx(1.0)
    integral = quad(lambda t: time_profile(t, T), 0, T)[0]
    assert total_impulse(5e4, T, 0.05) == pytest.approx(5e4 * 2 * 0.05 / np.pi * integral, rel=1e-10)

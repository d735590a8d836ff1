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

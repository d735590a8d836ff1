"""Precompressed chains in `granplate verify` (precompression_cases): the static state and
modes against statics and the band edges, and Nesterenko's solitary-wave speed against its
closed form (the formula's limit c0 as F_m -> F0 checked too), over a decade of F_m / F0."""

from __future__ import annotations

import pytest

from granplate.verification import all_cases
from granplate.verification.precompression_cases import (
    SPEED_RTOL,
    nesterenko_speed,
    solitary_wave,
    static_checks,
)


def test_nesterenko_speed_tends_to_the_sound_speed():
    """V_s -> c0 as the amplitude ratio -> 1 (the weakly nonlinear limit), and grows with it."""
    assert nesterenko_speed(500.0, 1.0001) == pytest.approx(500.0, rel=1e-4)
    assert nesterenko_speed(500.0, 2.0) < nesterenko_speed(500.0, 20.0)


def test_static_state_and_modes_pass():
    """Every check of the case `precompressed-chain` passes (statics, gravity, cut-off, gap)."""
    checks, _ = static_checks()
    assert all(c.passed for c in checks), [c for c in checks if not c.passed]


def test_solitary_waves_a_decade_apart_travel_at_nesterenkos_speed():
    """Two strikers, F_m / F0 about 2.6 and 32: each wave's speed within 1.5% of the closed form
    (at a step of 1e-7 s, 400 steps per contact period of the strongest wave)."""
    rows = [solitary_wave(v, step=1e-7) for v in (0.2, 1.5)]
    assert rows[1]["ratio"] / rows[0]["ratio"] >= 10.0
    for r in rows:
        assert r["speed"] == pytest.approx(r["theory"], rel=SPEED_RTOL)


def test_the_cases_are_registered():
    names = [c.name for c in all_cases()]
    assert "precompressed-chain" in names and "solitary-wave-speed" in names

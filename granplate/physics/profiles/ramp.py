"""The drive profile "ramp": P = value min(t / duration, 1)."""

from __future__ import annotations

from granplate.jit import njit
from granplate.physics.profiles import PAR_DURATION, PAR_VALUE


@njit(cache=True, inline="always")
def profile_terms(t, par, tab, n):
    """(int_0^t P, P, P', P'') of P = value min(t / T, 1), T = duration [s]."""
    value = par[PAR_VALUE]
    T = par[PAR_DURATION]
    if t < T:
        return 0.5 * value * t * t / T, value * t / T, value / T, 0.0
    return value * (t - 0.5 * T), value, 0.0, 0.0

"""The drive profile "half-sine": P = amplitude sin(pi t / duration) for t <= duration, 0 after."""

from __future__ import annotations

import math

from granplate.jit import njit
from granplate.physics.profiles import PAR_AMPLITUDE, PAR_DURATION


@njit(cache=True, inline="always")
def profile_terms(t, par, tab, n):
    """(int_0^t P, P, P', P'') of P = a sin(pi t / T) over t <= T, 0 after (a = amplitude, T = duration [s])."""
    a = par[PAR_AMPLITUDE]
    T = par[PAR_DURATION]
    k = math.pi / T
    if t <= T:
        return (
            a / k * (1.0 - math.cos(k * t)),
            a * math.sin(k * t),
            a * k * math.cos(k * t),
            -a * k * k * math.sin(k * t),
        )
    return 2.0 * a / k, 0.0, 0.0, 0.0

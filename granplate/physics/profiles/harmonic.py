"""The drive profile "harmonic": P = value + amplitude sin(2 pi frequency t)."""

from __future__ import annotations

import math

from granplate.jit import njit
from granplate.physics.profiles import PAR_AMPLITUDE, PAR_FREQUENCY, PAR_VALUE


@njit(cache=True, inline="always")
def profile_terms(t, par, tab, n):
    """(int_0^t P, P, P', P'') of P = value + a sin(w t), w = 2 pi frequency [rad/s]."""
    value = par[PAR_VALUE]
    a = par[PAR_AMPLITUDE]
    w = 2.0 * math.pi * par[PAR_FREQUENCY]
    s = math.sin(w * t)
    c = math.cos(w * t)
    return value * t + a / w * (1.0 - c), value + a * s, a * w * c, -a * w * w * s

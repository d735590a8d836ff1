"""The drive profile "constant": P = value."""

from __future__ import annotations

from granplate.jit import njit
from granplate.physics.profiles import PAR_VALUE


@njit(cache=True, inline="always")
def profile_terms(t, par, tab, n):
    """(int_0^t P, P, P', P'') of P = value."""
    value = par[PAR_VALUE]
    return value * t, value, 0.0, 0.0

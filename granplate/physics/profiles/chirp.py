"""The drive profile "chirp": P = amplitude sin(phi(t)) for t <= duration, held at P(duration)
after, phi = 2 pi (f0 t + (f1 - f0) t^2 / (2 T)): the frequency phi' / (2 pi) swept
linearly from f0 = frequency to f1 = frequency_end [Hz] over T = duration [s] (no
integral: a displacement or a force drive only)."""

from __future__ import annotations

import math

from granplate.jit import njit
from granplate.physics.profiles import PAR_AMPLITUDE, PAR_DURATION, PAR_FREQUENCY, PAR_FREQUENCY_END


@njit(cache=True)
def chirp_terms(t, a, f0, f1, T):
    """(0, P, P', P'') of the chirp P = a sin(phi), phi = 2 pi (f0 t + (f1 - f0) t^2 / (2 T)),
    for t <= T; held at P(T) after, so that a displacement stays continuous (its integral is
    not computed: 0)."""
    if t > T:
        return 0.0, a * math.sin(2.0 * math.pi * (f0 * T + 0.5 * (f1 - f0) * T)), 0.0, 0.0
    phi = 2.0 * math.pi * (f0 * t + 0.5 * (f1 - f0) * t * t / T)
    w = 2.0 * math.pi * (f0 + (f1 - f0) * t / T)
    dw = 2.0 * math.pi * (f1 - f0) / T
    s, c = math.sin(phi), math.cos(phi)
    return 0.0, a * s, a * w * c, a * (dw * c - w * w * s)


@njit(cache=True, inline="always")
def profile_terms(t, par, tab, n):
    """(0, P, P', P'') of the chirp (`chirp_terms`)."""
    return chirp_terms(t, par[PAR_AMPLITUDE], par[PAR_FREQUENCY], par[PAR_FREQUENCY_END], par[PAR_DURATION])

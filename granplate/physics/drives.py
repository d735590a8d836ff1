"""A drive's time profile and the motion it prescribes (docs/model.md section 3.11), as
compiled functions of arrays: a profile id, its parameters (PAR_* columns) and a table.

The profile P(t) [m, m/s or N] is one of
    constant   P = value
    ramp       P = value min(t / T, 1)
    half-sine  P = amplitude sin(pi t / T) for t <= T, 0 after
    harmonic   P = value + amplitude sin(2 pi f t)
    table      linear between the points (t_k, P_k); P_0 before them, the last after
    chirp      P = amplitude sin(phi(t)) for t <= T, P(T) after, phi = 2 pi (f0 t + (f1 - f0) t^2 / (2 T)):
               the frequency phi' / (2 pi) swept linearly from f0 to f1 (no integral: a
               displacement or a force drive only)
and `profile_terms` gives its integral from 0, its value, slope and curvature at t. A
displacement drive moves its body by s = P(t) - P(0) (velocity P', acceleration P''); a
velocity drive by s = int_0^t P (velocity P, acceleration P'); a force drive pushes with P
(a granule, or a wall that it makes a piston of mass PAR_MASS, solver.drives).
"""

from __future__ import annotations

import math

from granplate.jit import njit

#: profile ids (the order of setup.scenario.DRIVE_PROFILES)
PROFILE_CONSTANT, PROFILE_RAMP, PROFILE_HALF_SINE, PROFILE_HARMONIC, PROFILE_TABLE, PROFILE_CHIRP = range(6)
#: drive kinds (the order of setup.scenario.DRIVE_KINDS)
KIND_DISPLACEMENT, KIND_VELOCITY, KIND_FORCE = range(3)
#: columns of a drive's parameters: value, amplitude, frequency [Hz], duration [s], the
#: chirp's end frequency [Hz], and a force-driven wall's mass [kg] (a piston's; 0 otherwise)
PAR_VALUE, PAR_AMPLITUDE, PAR_FREQUENCY, PAR_DURATION, PAR_FREQUENCY_END, PAR_MASS = range(6)
N_PAR = 6
#: columns of a drive's table: the times [s], the values, the integral of the values from 0
TAB_T, TAB_V, TAB_I = range(3)


@njit(cache=True)
def table_terms(t, tab, n):
    """(integral from 0, value, slope) at t of the piecewise-linear table tab[:n] (columns
    TAB_T, TAB_V, TAB_I: its times, values and their integral from 0 at each time); at a
    point, the slope of the segment after it."""
    if t < tab[0, TAB_T]:
        v0 = tab[0, TAB_V]
        return v0 * t, v0, 0.0
    last = n - 1
    if t >= tab[last, TAB_T]:
        return tab[last, TAB_I] + tab[last, TAB_V] * (t - tab[last, TAB_T]), tab[last, TAB_V], 0.0
    lo = 0
    hi = last
    while hi - lo > 1:  # tab[lo, T] <= t < tab[hi, T]
        mid = (lo + hi) // 2
        if tab[mid, TAB_T] <= t:
            lo = mid
        else:
            hi = mid
    dt = t - tab[lo, TAB_T]
    slope = (tab[hi, TAB_V] - tab[lo, TAB_V]) / (tab[hi, TAB_T] - tab[lo, TAB_T])
    value = tab[lo, TAB_V] + slope * dt
    return tab[lo, TAB_I] + 0.5 * (tab[lo, TAB_V] + value) * dt, value, slope


@njit(entry=True, cache=True)
def profile_terms(t, pid, par, tab, n):
    """(int_0^t P, P(t), P'(t), P''(t)) of profile pid with parameters par (PAR_*) and
    table tab[:n] (profile "table" only), t >= 0 [s]."""
    value = par[PAR_VALUE]
    if pid == PROFILE_CONSTANT:
        return value * t, value, 0.0, 0.0
    if pid == PROFILE_RAMP:
        T = par[PAR_DURATION]
        if t < T:
            return 0.5 * value * t * t / T, value * t / T, value / T, 0.0
        return value * (t - 0.5 * T), value, 0.0, 0.0
    a = par[PAR_AMPLITUDE]
    if pid == PROFILE_HALF_SINE:
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
    if pid == PROFILE_HARMONIC:
        w = 2.0 * math.pi * par[PAR_FREQUENCY]
        s = math.sin(w * t)
        c = math.cos(w * t)
        return value * t + a / w * (1.0 - c), value + a * s, a * w * c, -a * w * w * s
    if pid == PROFILE_CHIRP:
        return chirp_terms(t, a, par[PAR_FREQUENCY], par[PAR_FREQUENCY_END], par[PAR_DURATION])
    integral, v, slope = table_terms(t, tab, n)
    return integral, v, slope, 0.0


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


@njit(entry=True, cache=True)
def drive_motion(t, kind, pid, par, tab, n):
    """What a drive prescribes at t [s]: (s, v, a) the displacement [m] from t = 0,
    velocity [m/s] and acceleration [m/s^2] of a displacement or velocity drive along its
    direction, or (0, 0, F) with the force F [N] of a force drive."""
    integral, p, dp, ddp = profile_terms(t, pid, par, tab, n)
    if kind == KIND_VELOCITY:
        return integral, p, dp
    if kind == KIND_DISPLACEMENT:
        _, p0, _, _ = profile_terms(0.0, pid, par, tab, n)
        return p - p0, dp, ddp
    return 0.0, 0.0, p

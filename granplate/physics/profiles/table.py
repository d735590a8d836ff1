"""The drive profile "table": P linear between the points (t_k, P_k) of the drive's table,
P_0 before them, the last value after."""

from __future__ import annotations

from granplate.jit import njit
from granplate.physics.profiles import TAB_I, TAB_T, TAB_V


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


@njit(cache=True, inline="always")
def profile_terms(t, par, tab, n):
    """(int_0^t P, P, P', 0) of the table (`table_terms`)."""
    integral, v, slope = table_terms(t, tab, n)
    return integral, v, slope, 0.0

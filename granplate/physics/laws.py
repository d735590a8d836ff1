"""The normal law of one contact, chosen by its coefficient row: Hertz's (eq. 2,
`contact.normal_response`) when the row's yield overlap COEF_DY is infinite, else the
elastic-plastic law of Thornton (docs/model.md section 3.6, `plastic.yielding_normal_response`)
with the contact's history, its largest overlap delta_max.

The time loop calls these for every contact kind (granule-granule, granule-wall,
granule-plate), so that a new normal law is one branch here and a coefficient column.
An infinite COEF_DY takes the Hertz branch unchanged: elastic runs stay bitwise what
they were before the plastic law existed.
"""
from __future__ import annotations

import math

from numba import njit

from granplate.physics.contact import COEF_A, COEF_C, COEF_DY, normal_force, normal_force_slopes, normal_response
from granplate.physics.plastic import yielding_normal_force, yielding_normal_response, yielding_normal_slopes


@njit(cache=True)
def normal_law_response(delta: float, delta_dot: float, coef, delta_max: float, clip: bool):
    """(|N| [N], viscous power [W], stored elastic energy [J], plastic work past delta_max [J])
    of one contact in touch (delta > 0) with coefficient row `coef` (physics.contact's
    columns) and largest overlap so far delta_max [m] (read only by the plastic law)."""
    delta_y = coef[COEF_DY]
    if delta_y == math.inf:
        n, pv, ep = normal_response(delta, delta_dot, coef[COEF_A], coef[COEF_C], clip)
        return n, pv, ep, 0.0
    return yielding_normal_response(delta, delta_dot, coef[COEF_A], coef[COEF_C], delta_y, delta_max, clip)


@njit(cache=True)
def normal_law_force(delta: float, delta_dot: float, coef, delta_max: float, clip: bool) -> float:
    """|N| [N] of `normal_law_response` alone."""
    delta_y = coef[COEF_DY]
    if delta_y == math.inf:
        return normal_force(delta, delta_dot, coef[COEF_A], coef[COEF_C], clip)[0]
    return yielding_normal_force(delta, delta_dot, coef[COEF_A], coef[COEF_C], delta_y, delta_max, clip)


@njit(cache=True)
def normal_law_slopes(delta: float, coef, delta_max: float):
    """dN/d(delta) [N/m] and dN/d(delta rate) [N s/m] of `normal_law_response` in touch."""
    delta_y = coef[COEF_DY]
    if delta_y == math.inf:
        return normal_force_slopes(delta, coef[COEF_A], coef[COEF_C])
    return yielding_normal_slopes(delta, coef[COEF_A], coef[COEF_C], delta_y, delta_max)

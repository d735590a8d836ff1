"""The normal law of one contact, chosen by its coefficient row: Hertz's (eq. 2,
`contact.normal_response`) when the row's yield overlap COEF_DY is infinite; else the
law "johnson" (docs/model.md section 3.10, `cavity.johnson_normal_response`) when the row
holds its force scale COEF_SY, else the elastic-plastic law of Thornton (docs/model.md
section 3.6, `plastic.yielding_normal_response`), each with the contact's history: its
largest overlap delta_max and, for "johnson", the rate factor Y(rate) / Y that fixed its
yield strength (0: not yet fixed).

The time loop calls these for every contact kind (granule-granule, granule-wall,
granule-plate, granule-body), so that a new normal law is one branch here and coefficient
columns. An infinite COEF_DY takes the Hertz branch unchanged: elastic runs stay bitwise
what they were before the plastic laws existed.

Cost (docs/benchmarks.md, "Contacts that yield"): a contact whose overlap and largest
overlap are both at or below COEF_DY takes Hertz's code here, before any plastic law is
entered: the same result as the laws' own elastic branches (Thornton's yields at COEF_DY;
the yield overlap of "johnson", COEF_DY (Y(rate) / Y)^2, is never below COEF_DY since
C >= 0), without their history arithmetic or the rate factor's logarithm. The plastic laws'
responses are compiled inline into these functions (`inline="always"`), so a contact past
yield costs one call from the loop, as a Hertz contact does.
"""

from __future__ import annotations

import math

from numba import njit

from granplate.physics.cavity import johnson_normal_force, johnson_normal_response, johnson_normal_slopes
from granplate.physics.contact import (
    COEF_A,
    COEF_C,
    COEF_DY,
    COEF_SY,
    normal_force,
    normal_force_slopes,
    normal_response,
)
from granplate.physics.plastic import yielding_normal_force, yielding_normal_response, yielding_normal_slopes


@njit(cache=True)
def normal_law_response(delta: float, delta_dot: float, coef, delta_max: float, rate: float, clip: bool):
    """(|N| [N], viscous power [W], stored elastic energy [J], plastic work past delta_max [J])
    of one contact in touch (delta > 0) with coefficient row `coef` (physics.contact's
    columns), largest overlap so far delta_max [m] and rate factor `rate` (Y(rate) / Y, 0 while
    unset; both read only by the plastic laws)."""
    delta_y = coef[COEF_DY]
    if delta <= delta_y and delta_max <= delta_y:  # Hertz (delta_y inf) or an elastic history
        n, pv, ep = normal_response(delta, delta_dot, coef[COEF_A], coef[COEF_C], clip)
        return n, pv, ep, 0.0
    if coef[COEF_SY] > 0.0:
        return johnson_normal_response(delta, delta_dot, coef, delta_max, rate, clip)
    return yielding_normal_response(delta, delta_dot, coef[COEF_A], coef[COEF_C], delta_y, delta_max, clip)


@njit(cache=True)
def normal_law_force(delta: float, delta_dot: float, coef, delta_max: float, rate: float, clip: bool) -> float:
    """|N| [N] of `normal_law_response` alone."""
    delta_y = coef[COEF_DY]
    if delta <= delta_y and delta_max <= delta_y:  # Hertz (delta_y inf) or an elastic history
        return normal_force(delta, delta_dot, coef[COEF_A], coef[COEF_C], clip)[0]
    if coef[COEF_SY] > 0.0:
        return johnson_normal_force(delta, delta_dot, coef, delta_max, rate, clip)
    return yielding_normal_force(delta, delta_dot, coef[COEF_A], coef[COEF_C], delta_y, delta_max, clip)


@njit(cache=True)
def normal_law_slopes(delta: float, coef, delta_max: float, rate: float):
    """dN/d(delta) [N/m] and dN/d(delta rate) [N s/m] of `normal_law_response` in touch."""
    delta_y = coef[COEF_DY]
    if delta_y == math.inf:
        return normal_force_slopes(delta, coef[COEF_A], coef[COEF_C])
    if coef[COEF_SY] > 0.0:
        return johnson_normal_slopes(delta, coef, delta_max, rate)
    return yielding_normal_slopes(delta, coef[COEF_A], coef[COEF_C], delta_y, delta_max)

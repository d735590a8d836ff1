"""The normal law of one contact, chosen by its law id, the coefficient row's column
COEF_NLAW (setup.law_registry's NORMAL_LAW_IDS): Hertz's (eq. 2, `contact.normal_response`),
the law "johnson" (docs/model.md section 3.10, `cavity.johnson_normal_response`) or the
elastic-plastic law of Thornton (docs/model.md section 3.6, `plastic.yielding_normal_response`),
each with the contact's history: its largest overlap delta_max and, for "johnson", the rate
factor Y(rate) / Y that fixed its yield strength (0: not yet fixed). One dispatch function
per response kind: `normal_law_response` (force, viscous power, stored energy, plastic
work), `normal_law_force` (the force alone) and `normal_law_slopes` (Newton's slopes).

The time loop calls these for every contact kind (granule-granule, granule-wall,
granule-plate, granule-body), so that a new normal law is its module, its id in the
registry and one branch in each function here (docs/architecture.md, "Adding a normal
law"). A Hertz contact takes the Hertz branch after one compare of its law id: elastic runs
stay bitwise what they were before the plastic laws existed.

Cost (docs/benchmarks.md, "Contacts that yield"): a contact under a yielding law whose
overlap and largest overlap are both at or below its yield overlap COEF_DY takes Hertz's
code here, before any plastic law is entered: the same result as the laws' own elastic
branches (Thornton's yields at COEF_DY; the yield overlap of "johnson", COEF_DY (Y(rate) /
Y)^2, is never below COEF_DY since C >= 0), without their history arithmetic or the rate
factor's logarithm. The plastic laws' responses are compiled inline into these functions
(`inline="always"`), so a contact past yield costs one call from the loop, as a Hertz
contact does.
"""

from __future__ import annotations

from granplate.jit import njit

from granplate.physics.cavity import johnson_normal_force, johnson_normal_response, johnson_normal_slopes
from granplate.physics.contact import (
    COEF_A,
    COEF_C,
    COEF_DY,
    COEF_NLAW,
    normal_force,
    normal_force_slopes,
    normal_response,
)
from granplate.physics.plastic import yielding_normal_force, yielding_normal_response, yielding_normal_slopes
from granplate.setup.law_registry import HERTZ, JOHNSON


@njit(cache=True)
def normal_law_response(delta: float, delta_dot: float, coef, delta_max: float, rate: float, clip: bool):
    """(|N| [N], viscous power [W], stored elastic energy [J], plastic work past delta_max [J])
    of one contact in touch (delta > 0) with coefficient row `coef` (physics.contact's
    columns), largest overlap so far delta_max [m] and rate factor `rate` (Y(rate) / Y, 0 while
    unset; both read only by the plastic laws)."""
    law = coef[COEF_NLAW]
    delta_y = coef[COEF_DY]
    if law == HERTZ or (delta <= delta_y and delta_max <= delta_y):  # Hertz, or an elastic history
        n, pv, ep = normal_response(delta, delta_dot, coef[COEF_A], coef[COEF_C], clip)
        return n, pv, ep, 0.0
    if law == JOHNSON:
        return johnson_normal_response(delta, delta_dot, coef, delta_max, rate, clip)
    return yielding_normal_response(delta, delta_dot, coef[COEF_A], coef[COEF_C], delta_y, delta_max, clip)


@njit(cache=True)
def normal_law_force(delta: float, delta_dot: float, coef, delta_max: float, rate: float, clip: bool) -> float:
    """|N| [N] of `normal_law_response` alone."""
    law = coef[COEF_NLAW]
    delta_y = coef[COEF_DY]
    if law == HERTZ or (delta <= delta_y and delta_max <= delta_y):  # Hertz, or an elastic history
        return normal_force(delta, delta_dot, coef[COEF_A], coef[COEF_C], clip)[0]
    if law == JOHNSON:
        return johnson_normal_force(delta, delta_dot, coef, delta_max, rate, clip)
    return yielding_normal_force(delta, delta_dot, coef[COEF_A], coef[COEF_C], delta_y, delta_max, clip)


@njit(cache=True)
def normal_law_slopes(delta: float, coef, delta_max: float, rate: float):
    """dN/d(delta) [N/m] and dN/d(delta rate) [N s/m] of `normal_law_response` in touch."""
    law = coef[COEF_NLAW]
    if law == HERTZ:
        return normal_force_slopes(delta, coef[COEF_A], coef[COEF_C])
    if law == JOHNSON:
        return johnson_normal_slopes(delta, coef, delta_max, rate)
    return yielding_normal_slopes(delta, coef[COEF_A], coef[COEF_C], coef[COEF_DY], delta_max)

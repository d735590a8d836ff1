"""Hertz's normal law (eq. 2 with eq. 3's damping) as a registered normal law: the
interface every normal law module gives physics.laws (docs/architecture.md, "Adding a
normal law"). The law itself is physics.contact's (`normal_force`, `normal_response`,
`normal_force_slopes`); here it takes the common arguments: the overlap delta [m], its rate
[m/s], the contact's coefficient row `coef` (physics.contact's columns), its largest overlap
delta_max [m] and rate factor `rate` (both unused: Hertz's law has no history), and `clip`
(no tensile force).
"""

from __future__ import annotations

import math

import numpy as np

from granplate.jit import njit
from granplate.physics.contact import (
    COEF_A,
    COEF_C,
    N_LAW_COLUMNS,
    normal_force,
    normal_force_slopes,
    normal_response,
)


@njit(cache=True, inline="always")
def law_response(delta: float, delta_dot: float, coef, delta_max: float, rate: float, clip: bool):
    """(|N| [N], viscous power [W], stored energy [J], plastic work 0 [J]) in touch, eqs. (2), (9), (10)."""
    n, pv, ep = normal_response(delta, delta_dot, coef[COEF_A], coef[COEF_C], clip)
    return n, pv, ep, 0.0


@njit(cache=True, inline="always")
def law_force(delta: float, delta_dot: float, coef, delta_max: float, rate: float, clip: bool) -> float:
    """|N| [N] of eq. (2) in touch."""
    return normal_force(delta, delta_dot, coef[COEF_A], coef[COEF_C], clip)[0]


@njit(cache=True, inline="always")
def law_slopes(delta: float, coef, delta_max: float, rate: float):
    """dN/d(delta) [N/m] and dN/d(delta rate) [N s/m] of eq. (2) in touch."""
    return normal_force_slopes(delta, coef[COEF_A], coef[COEF_C])


@njit(cache=True, inline="always")
def law_rate(d: float, d_old: float, t: float, t_old: float, rate: float, coef) -> float:
    """The rate factor once the largest overlap grows from d_old (at t_old) to d (at t):
    unchanged (no rate dependence)."""
    return rate


def law_columns(softer, e_star: float, r_star: float, length: float) -> np.ndarray:
    """The law's columns COEF_DY..COEF_XH: a yield overlap never reached (inf), no parameters."""
    out = np.zeros(N_LAW_COLUMNS)
    out[0] = math.inf
    return out

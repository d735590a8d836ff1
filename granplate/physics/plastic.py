"""The elastic-plastic normal law of Thornton (1997), docs/model.md section 3.6.

Thornton, C. (1997) Coefficient of restitution for collinear collisions of elastic-
perfectly plastic spheres, J. Appl. Mech. 64, 383-386. One small pure function per
equation (P1)-(P10) of docs/model.md, compiled by numba and callable from Python, so that a
contact loop and the tests use the very same code. Units: metres, newtons, joules, pascals.

The law depends on the overlap delta and its history alone (the largest overlap so far,
delta_max), through two coefficients of the contact:

- A = 4/3 E* sqrt(R*) [N/m^(3/2)], the Hertz coefficient of eq. (3) (`contact.hertz_coefficient`);
- delta_y [m], the yield overlap (P3), from E*, R* and the limiting pressure
  p_y = 1.6 Y of the softer body (P1); delta_y = inf (Y unknown or infinite) is Hertz,
  bitwise: every branch below delta_y is `contact.hertz_elastic`.

Loading above delta_y follows F = F_y + pi p_y R* (delta - delta_y) (P5); unloading and
reloading below delta_max follow a Hertz curve of the enlarged radius R_p (P6) from the
residual overlap delta_p (P7), continuous with the loading curve at delta_max (P8). The
stored elastic energy (P9) plus the plastic work W_p(delta_max) (P10) equal the work done
on the contact along any path. Nothing here knows the dimension: the same functions serve
a contact in the plane or in space.

A contact loop calls `plastic_response` (force and slope in one call) with the history of
the contact, then `updated_max_overlap` once the state is accepted; the energy bookkeeping
uses `plastic_elastic_energy` (stored, part of E_granular) and `plastic_work`
(dissipated). `contact_yield_overlap` gives delta_y from E*, R* and the softer body's Y.
"""

from __future__ import annotations

import math

import numpy as np

from granplate.jit import njit

from granplate.physics.contact import (
    COEF_A,
    COEF_C,
    COEF_DY,
    N_LAW_COLUMNS,
    contact_energy,
    hertz_elastic,
    normal_force,
    normal_response,
)

#: p_y / Y: the Hertz peak pressure at which yield starts under a sphere, p0 = 1.6 Y
#: (von Mises, nu = 0.3; Johnson, Contact Mechanics, 1985, section 6.2), taken by Thornton
#: as the limiting contact pressure of the plastic law (P1).
YIELD_ONSET_FACTOR = 1.6


@njit(entry=True, cache=True)
def limiting_pressure(y_strength: float) -> float:
    """p_y = 1.6 Y [Pa] (P1), Y: the yield strength of the softer body [Pa]."""
    return YIELD_ONSET_FACTOR * y_strength


@njit(entry=True, cache=True)
def hertz_peak_pressure(e_star: float, r_star: float, delta: float) -> float:
    """Hertz's peak contact pressure p0 = (2/pi) E* sqrt(delta / R*) [Pa] (P2); 0 out of touch."""
    if delta <= 0.0:
        return 0.0
    return 2.0 / math.pi * e_star * math.sqrt(delta / r_star)


@njit(cache=True)
def yield_onset_ratio(e_star: float, r_star: float, delta: float, y_strength: float) -> float:
    """p0 / (1.6 Y) [-] (P2 over P1): above 1 a Hertz contact has started to yield."""
    return hertz_peak_pressure(e_star, r_star, delta) / limiting_pressure(y_strength)


@njit(entry=True, cache=True)
def yield_overlap(e_star: float, r_star: float, p_y: float) -> float:
    """delta_y = (pi p_y / (2 E*))^2 R* [m] (P3): the overlap at which p0 reaches p_y."""
    q = math.pi * p_y / (2.0 * e_star)
    return q * q * r_star


def contact_yield_overlap(e_star: float, r_star: float, y_strength: float | None) -> float:
    """delta_y [m] (P3 with P1) of a contact whose softer body has yield strength Y [Pa]
    (`setup.materials.softer_yield_strength`); inf when Y is unknown (None) or infinite:
    the law is then Hertz's. Plain Python: for building a contact's coefficients."""
    if y_strength is None or math.isinf(y_strength):
        return math.inf
    return yield_overlap(e_star, r_star, limiting_pressure(y_strength))


@njit(cache=True)
def yield_force(a: float, delta_y: float) -> float:
    """F_y = A delta_y^(3/2) = pi^3 p_y^3 R*^2 / (6 E*^2) [N] (P4)."""
    return hertz_elastic(delta_y, a)


@njit(cache=True)
def plastic_stiffness(a: float, delta_y: float) -> float:
    """k_p = pi p_y R* = 3/2 A delta_y^(1/2) [N/m], the slope of the loading line (P5),
    equal to the Hertz slope at delta_y."""
    return 1.5 * a * math.sqrt(delta_y)


@njit(entry=True, cache=True)
def loading_force(a: float, delta_y: float, delta: float) -> float:
    """The virgin loading curve [N] (P5): A delta^(3/2) up to delta_y, then
    F_y + k_p (delta - delta_y)."""
    if delta <= delta_y:
        return hertz_elastic(delta, a)
    return yield_force(a, delta_y) + plastic_stiffness(a, delta_y) * (delta - delta_y)


@njit(cache=True)
def unloading_span(delta_y: float, delta_max: float) -> float:
    """delta_max - delta_p [m] (P7): the elastic part of the largest overlap,
    (3/2 delta_max - 1/2 delta_y) sqrt(delta_y / delta_max); delta_max itself below delta_y."""
    if delta_max <= delta_y:
        return delta_max
    return (1.5 * delta_max - 0.5 * delta_y) * math.sqrt(delta_y / delta_max)


@njit(entry=True, cache=True)
def residual_overlap(delta_y: float, delta_max: float) -> float:
    """delta_p [m] (P7): the overlap at which the unloading curve from delta_max reaches
    zero force (the permanent flattening); 0 while delta_max <= delta_y."""
    if delta_max <= delta_y:
        return 0.0
    return delta_max - unloading_span(delta_y, delta_max)


@njit(cache=True)
def unloading_radius(r_star: float, a: float, delta_y: float, delta_max: float) -> float:
    """R_p [m] (P6): the radius of the Hertz unloading curve from delta_max,
    R_p = 4 E* a_p^3 / (3 F_max) with a_p^2 = R* delta_max = (2 F_max + F_y) / (2 pi p_y),
    written here as R* F_max^2 / (A^2 (delta_max - delta_p)^3); R* while delta_max <= delta_y."""
    if delta_max <= delta_y:
        return r_star
    f_max = loading_force(a, delta_y, delta_max)
    w = unloading_span(delta_y, delta_max)
    return r_star * f_max * f_max / (a * a * w * w * w)


@njit(cache=True)
def updated_max_overlap(delta: float, delta_max: float) -> float:
    """The contact's history after an accepted state: max(delta, delta_max) [m]."""
    return delta if delta > delta_max else delta_max


@njit(entry=True, cache=True)
def plastic_force(a: float, delta_y: float, delta: float, delta_max: float) -> float:
    """Normal force of the elastic-plastic law [N] (P8) at overlap delta with history
    delta_max (the largest overlap before; delta > delta_max is loading).

    Elastic history (max(delta, delta_max) <= delta_y): A delta^(3/2), Hertz. Loading
    (delta >= delta_max, delta > delta_y): the loading curve (P5). Below delta_max:
    F_max ((delta - delta_p) / (delta_max - delta_p))^(3/2), zero for delta <= delta_p.
    """
    m = updated_max_overlap(delta, delta_max)
    if m <= delta_y:
        return hertz_elastic(delta, a)
    if delta >= m:
        return loading_force(a, delta_y, delta)
    w = unloading_span(delta_y, m)
    d = delta - (m - w)
    if d <= 0.0:
        return 0.0
    return loading_force(a, delta_y, m) * d * math.sqrt(d) / (w * math.sqrt(w))


@njit(cache=True)
def plastic_force_slope(a: float, delta_y: float, delta: float, delta_max: float) -> float:
    """dF/d delta [N/m] of `plastic_force` (the implicit scheme's Newton needs it).

    At delta >= delta_max > delta_y the loading slope k_p (the derivative for a growing
    overlap; unloading from there is stiffer, 3/2 F_max / (delta_max - delta_p)).
    """
    m = updated_max_overlap(delta, delta_max)
    if m <= delta_y:
        if delta <= 0.0:
            return 0.0
        return 1.5 * a * math.sqrt(delta)
    if delta >= m:
        return plastic_stiffness(a, delta_y)
    w = unloading_span(delta_y, m)
    d = delta - (m - w)
    if d <= 0.0:
        return 0.0
    return 1.5 * loading_force(a, delta_y, m) * math.sqrt(d) / (w * math.sqrt(w))


@njit(cache=True)
def plastic_response(a: float, delta_y: float, delta: float, delta_max: float):
    """(F [N], dF/d delta [N/m]) of `plastic_force` and `plastic_force_slope` in one call,
    the unloading curve computed once (what a contact loop needs per evaluation)."""
    m = updated_max_overlap(delta, delta_max)
    if m <= delta_y:
        if delta <= 0.0:
            return 0.0, 0.0
        sq = math.sqrt(delta)
        return a * delta * sq, 1.5 * a * sq
    if delta >= m:
        return loading_force(a, delta_y, delta), plastic_stiffness(a, delta_y)
    w = unloading_span(delta_y, m)
    d = delta - (m - w)
    if d <= 0.0:
        return 0.0, 0.0
    scale = loading_force(a, delta_y, m) / (w * math.sqrt(w))
    sq = math.sqrt(d)
    return scale * d * sq, 1.5 * scale * sq


@njit(cache=True)
def plastic_elastic_energy(a: float, delta_y: float, delta: float, delta_max: float) -> float:
    """Elastic energy stored in the contact [J] (P9): 2/5 A delta^(5/2) for an elastic
    history, else 2/5 F_max (delta - delta_p)^(5/2) / (delta_max - delta_p)^(3/2)
    (zero for delta <= delta_p), with delta_max updated by delta (as `plastic_force`)."""
    m = updated_max_overlap(delta, delta_max)
    if m <= delta_y:
        return contact_energy(delta, a)
    w = unloading_span(delta_y, m)
    d = delta - (m - w)
    if d <= 0.0:
        return 0.0
    return 0.4 * loading_force(a, delta_y, m) * d * d * math.sqrt(d) / (w * math.sqrt(w))


@njit(entry=True, cache=True)
def plastic_work(a: float, delta_y: float, delta_max: float) -> float:
    """Plastic work W_p(delta_max) [J] (P10): the work of the loading curve up to
    delta_max less the elastic energy it stores there,
    2/5 F_y delta_y + F_y (m - delta_y) + k_p (m - delta_y)^2 / 2 - 2/5 F_max (m - delta_p)
    with m = delta_max; 0 while delta_max <= delta_y. Non-decreasing in delta_max."""
    m = delta_max
    if m <= delta_y:
        return 0.0
    f_y = yield_force(a, delta_y)
    x = m - delta_y
    loading_work = 0.4 * f_y * delta_y + f_y * x + 0.5 * plastic_stiffness(a, delta_y) * x * x
    return loading_work - 0.4 * loading_force(a, delta_y, m) * unloading_span(delta_y, m)


@njit(cache=True, inline="always")
def yielding_normal_response(
    delta: float, delta_dot: float, a: float, c: float, delta_y: float, delta_max: float, clip: bool
):
    """The elastic-plastic law of one contact in touch (delta > 0) with the paper's
    damping (P13): |N| = F(delta, delta_max) (P8) + c (delta - delta_p)^(1/4) d(delta)/dt
    while delta > delta_p, 0 at or below the residual overlap delta_p; with clip, |N| >= 0.
    For an elastic history (delta_p = 0) this is eq. (2), in the same operations.

    Returns (|N| [N], viscous power [W] (as `contact.viscous_power`), stored elastic energy
    [J] (P9), plastic work [J] done past delta_max, W_p(max(delta, delta_max)) - W_p(delta_max)
    (P10), which is zero unless the contact loads past its largest overlap). One pass: the
    unloading curve of max(delta, delta_max) (P7, P8) is computed once.
    """
    m = updated_max_overlap(delta, delta_max)
    if m <= delta_y:  # an elastic history: Hertz, eqs. (2) and (9)
        n, pv, ep = normal_response(delta, delta_dot, a, c, clip)
        return n, pv, ep, 0.0
    w_p = 0.0
    if m > delta_max:
        w_p = plastic_work(a, delta_y, m) - plastic_work(a, delta_y, delta_max)
    w = unloading_span(delta_y, m)
    d_el = delta - (m - w)
    if d_el <= 0.0:
        return 0.0, 0.0, 0.0, w_p
    sq = math.sqrt(d_el)
    scale = loading_force(a, delta_y, m) / (w * math.sqrt(w))
    f = scale * d_el * sq
    n = f + c * math.sqrt(sq) * delta_dot
    if clip and n < 0.0:
        n = 0.0
    return n, (n - f) * delta_dot, 0.4 * f * d_el, w_p


@njit(cache=True, inline="always")
def yielding_normal_force(
    delta: float, delta_dot: float, a: float, c: float, delta_y: float, delta_max: float, clip: bool
) -> float:
    """|N| [N] of `yielding_normal_response` alone (no energies: what friction needs)."""
    m = updated_max_overlap(delta, delta_max)
    if m <= delta_y:
        return normal_force(delta, delta_dot, a, c, clip)[0]
    w = unloading_span(delta_y, m)
    d_el = delta - (m - w)
    if d_el <= 0.0:
        return 0.0
    sq = math.sqrt(d_el)
    f = loading_force(a, delta_y, m) / (w * math.sqrt(w)) * d_el * sq
    n = f + c * math.sqrt(sq) * delta_dot
    return 0.0 if clip and n < 0.0 else n


@njit(cache=True)
def yielding_normal_slopes(delta: float, a: float, c: float, delta_y: float, delta_max: float):
    """dN/d(delta) [N/m] (`plastic_force_slope`) and dN/d(delta rate) = c (delta - delta_p)^(1/4)
    [N s/m] of `yielding_normal_response` in touch (the implicit scheme's Newton)."""
    d_el = delta - residual_overlap(delta_y, updated_max_overlap(delta, delta_max))
    if d_el <= 0.0:
        return 0.0, 0.0
    return plastic_force_slope(a, delta_y, delta, delta_max), c * math.sqrt(math.sqrt(d_el))


# The law as a registered normal law ("thornton"; docs/architecture.md, "Adding a normal
# law"): the common arguments of physics.laws, the coefficient row holding A, c and
# delta_y. A contact whose overlap and largest overlap are both at or below delta_y takes
# Hertz's code at once, before any plastic arithmetic.


@njit(cache=True, inline="always")
def law_response(delta: float, delta_dot: float, coef, delta_max: float, rate: float, clip: bool):
    """`yielding_normal_response` of the row `coef` (rate unused)."""
    delta_y = coef[COEF_DY]
    if delta <= delta_y and delta_max <= delta_y:  # an elastic history: Hertz, eqs. (2) and (9)
        n, pv, ep = normal_response(delta, delta_dot, coef[COEF_A], coef[COEF_C], clip)
        return n, pv, ep, 0.0
    return yielding_normal_response(delta, delta_dot, coef[COEF_A], coef[COEF_C], delta_y, delta_max, clip)


@njit(cache=True, inline="always")
def law_force(delta: float, delta_dot: float, coef, delta_max: float, rate: float, clip: bool) -> float:
    """`yielding_normal_force` of the row `coef` (rate unused)."""
    delta_y = coef[COEF_DY]
    if delta <= delta_y and delta_max <= delta_y:
        return normal_force(delta, delta_dot, coef[COEF_A], coef[COEF_C], clip)[0]
    return yielding_normal_force(delta, delta_dot, coef[COEF_A], coef[COEF_C], delta_y, delta_max, clip)


@njit(cache=True, inline="always")
def law_slopes(delta: float, coef, delta_max: float, rate: float):
    """`yielding_normal_slopes` of the row `coef` (rate unused)."""
    return yielding_normal_slopes(delta, coef[COEF_A], coef[COEF_C], coef[COEF_DY], delta_max)


@njit(cache=True, inline="always")
def law_rate(d: float, d_old: float, t: float, t_old: float, rate: float, coef) -> float:
    """The rate factor as the largest overlap grows: unchanged (Y is rate-free here)."""
    return rate


def law_columns(softer, e_star: float, r_star: float, length: float) -> np.ndarray:
    """The law's columns COEF_DY..COEF_XH: the yield overlap delta_y [m] (P3) of the softer
    body (`softer`, a Material with its Y; E* [Pa], R* [m]), no other parameter."""
    out = np.zeros(N_LAW_COLUMNS)
    out[0] = contact_yield_overlap(e_star, r_star, softer.Y)
    return out

"""The elastic-plastic normal law "johnson": Hertz to yield, Johnson's expanding-cavity
mean pressure over the plastic contact disc up to the hardness, a rate-dependent yield
strength (docs/model.md section 3.10).

Sources: the onset of yield at the Hertz peak pressure 1.6 Y (Johnson, Contact Mechanics,
1985, section 6.2, as Thornton 1997); the mean pressure of an elastic-plastic indentation
p_m = (2/3) Y [1 + ln(E* a / (3 Y R*))] (Johnson's expanding-cavity model, Johnson 1970,
J. Mech. Phys. Solids 18, 115; Contact Mechanics eq. 6.42 with tan(beta) = a / R*) capped
at the fully plastic hardness h Y (Tabor, The Hardness of Metals, 1951: h near 2.8); the
plastic contact disc of a flattened cap a^2 = 2 R* delta; elastic unloading of that disc
along a Hertz curve (as Thornton 1997); the yield strength's strain-rate dependence
Y(rate) = Y [1 + C ln(rate / rate_ref)] (Burgoyne & Daraio 2014, Phys. Rev. E 89, 032203).

Everything is written in the contact's own scales: the overlap in units of the yield
overlap delta_y, x = delta / delta_y, the force in units of R* Y delta_y; then the loading
curve f(x), its slope, its work and the unloading span are functions of x and the hardness
ratio h alone (eqs. J1-J8 of docs/model.md). Between x = 1 and x = X_BRIDGE a cubic joins
Hertz's force and slope at yield to the cavity curve's (force and slope continuous).

A contact's coefficient row holds delta_y at the rate-free Y (COEF_DY), R* Y (COEF_SY),
the rate coefficient C (COEF_RC), 1 / (L rate_ref) with L the length over which the
approach speed is a strain rate (COEF_RL: the sum of the two radii, or the diameter
against a rigid body), h (COEF_H), the unloading factor kappa (COEF_KAPPA) and x_h
(COEF_XH, `hardness_overlap(h)`). Its
history holds the largest overlap delta_max and the rate factor phi = Y(rate) / Y fixed from
the approach speed (`rate_factor`): 0 while unset (then the current approach speed gives it,
which happens only while the contact is elastic), 1 for a rate-free contact. Units: metres,
newtons, joules.
"""

from __future__ import annotations

import math

import numpy as np
from granplate.jit import njit

from granplate.physics.contact import (
    COEF_A,
    COEF_C,
    COEF_DY,
    COEF_H,
    COEF_KAPPA,
    COEF_RC,
    COEF_RL,
    COEF_SY,
    COEF_XH,
    N_LAW_COLUMNS,
    normal_force,
    normal_response,
)
from granplate.physics.plastic import contact_yield_overlap
from granplate.setup.materials import DEFAULT_HARDNESS_RATIO, DEFAULT_UNLOADING_FACTOR

#: the Hertz force and slope at yield in units of R* Y delta_y and R* Y (J2): F_y = 2/3 pi p_y
#: R* delta_y and k_y = pi p_y R* with p_y = 1.6 Y
F_YIELD = 2.0 / 3.0 * 1.6 * math.pi
K_YIELD = 1.6 * math.pi
#: ln(E* a / (3 Y R*)) at a^2 = 2 R* delta_y, where E* sqrt(delta_y / R*) / Y = 0.8 pi (J3)
CAVITY_LOG0 = math.log(0.8 * math.pi * math.sqrt(2.0) / 3.0)
#: the end of the cubic bridge from Hertz at yield to the cavity curve, x = delta / delta_y
X_BRIDGE = 4.0
#: the unloading span's scale: E* a / (R* Y delta_y) = 0.8 pi sqrt(2 x) (J7)
SPAN_SCALE = 0.8 * math.pi


@njit(cache=True)
def cavity_pressure(x: float) -> float:
    """p_m / Y of the expanding-cavity model at x = delta / delta_y over the disc
    a^2 = 2 R* delta (J3): (2/3) [1 + ln(E* a / (3 Y R*))]."""
    return 2.0 / 3.0 * (1.0 + CAVITY_LOG0 + 0.5 * math.log(x))


@njit(entry=True, cache=True)
def hardness_overlap(h: float) -> float:
    """x_h: where the cavity pressure reaches the hardness h Y (J4)."""
    return math.exp(2.0 * (1.5 * h - 1.0 - CAVITY_LOG0))


def _bridge_constants():
    """(c2, c3, loading work to X_BRIDGE) of the cubic bridge (J5, J6): the same for every
    hardness ratio h the law accepts, since the cavity pressure at X_BRIDGE, 1.24 Y, lies
    below any h >= 1.5 (validation's range), so the cap is never reached on the bridge."""
    p = 2.0 / 3.0 * (1.0 + CAVITY_LOG0 + 0.5 * math.log(X_BRIDGE))
    f1, k1 = 2.0 * math.pi * X_BRIDGE * p, 2.0 * math.pi * (p + 1.0 / 3.0)
    span = X_BRIDGE - 1.0
    secant = (f1 - F_YIELD) / span
    c2 = (3.0 * secant - 2.0 * K_YIELD - k1) / span
    c3 = (K_YIELD + k1 - 2.0 * secant) / (span * span)
    w = 0.4 * F_YIELD + span * (F_YIELD + span * (0.5 * K_YIELD + span * (c2 / 3.0 + 0.25 * span * c3)))
    return c2, c3, w


#: the bridge's cubic coefficients and the loading work from 0 to X_BRIDGE (J5, J6)
BRIDGE_C2, BRIDGE_C3, BRIDGE_WORK = _bridge_constants()
#: the lowest hardness ratio for which the bridge constants hold (the cavity pressure at X_BRIDGE)
H_BRIDGE = 2.0 / 3.0 * (1.0 + CAVITY_LOG0 + 0.5 * math.log(X_BRIDGE))


@njit(cache=True)
def cavity_force(x: float, h: float, xh: float):
    """(f, df/dx) of the cavity curve f = 2 pi x min(h, p_m / Y) for x >= X_BRIDGE (J4);
    xh = `hardness_overlap(h)`, where the cap begins."""
    if x >= xh:
        return 2.0 * math.pi * x * h, 2.0 * math.pi * h
    p = cavity_pressure(x)
    return 2.0 * math.pi * x * p, 2.0 * math.pi * (p + 1.0 / 3.0)


@njit(cache=True)
def cavity_primitive(u: float) -> float:
    """The integral of the uncapped cavity curve 2 pi x p_m(x) / Y from 0 to u (J6)."""
    return 4.0 * math.pi / 3.0 * u * u * (0.5 * (1.0 + CAVITY_LOG0) + 0.25 * math.log(u) - 0.125)


@njit(cache=True)
def cavity_work(x: float, h: float, xh: float) -> float:
    """The integral of the cavity curve (J4) from X_BRIDGE to x >= X_BRIDGE (J6)."""
    u = x if x < xh else xh
    w = cavity_primitive(u) - cavity_primitive(X_BRIDGE)
    if x > xh:
        w += math.pi * h * (x * x - xh * xh)
    return w


@njit(cache=True)
def loading_force(x: float, h: float, xh: float):
    """(f, df/dx) of the virgin loading curve at x >= 1 in the contact's units (J4, J5):
    the cubic bridge up to X_BRIDGE, then the cavity curve."""
    if x <= X_BRIDGE:
        s = x - 1.0
        return (
            F_YIELD + s * (K_YIELD + s * (BRIDGE_C2 + s * BRIDGE_C3)),
            K_YIELD + s * (2.0 * BRIDGE_C2 + 3.0 * s * BRIDGE_C3),
        )
    return cavity_force(x, h, xh)


@njit(cache=True)
def loading_work(x: float, h: float, xh: float) -> float:
    """The virgin loading curve's work from 0 to x >= 1 in the contact's units (J6)."""
    if x <= X_BRIDGE:
        s = x - 1.0
        return 0.4 * F_YIELD + s * (F_YIELD + s * (0.5 * K_YIELD + s * (BRIDGE_C2 / 3.0 + 0.25 * s * BRIDGE_C3)))
    return BRIDGE_WORK + cavity_work(x, h, xh)


@njit(cache=True)
def loading_curve(x: float, h: float):
    """(f, df/dx, work from 0) of the virgin loading curve at x >= 1 (J4-J6)."""
    xh = hardness_overlap(h)
    f, k = loading_force(x, h, xh)
    return f, k, loading_work(x, h, xh)


@njit(cache=True)
def unloading_span(x: float, f: float, kappa: float) -> float:
    """omega = (delta_max - delta_p) / delta_y (J7): 1 + kappa (f - F_y) / (E* a) in the
    contact's units with a^2 = 2 R* delta_max; 1 at yield (Hertz's unloading)."""
    return 1.0 + kappa * (f - F_YIELD) / (SPAN_SCALE * math.sqrt(2.0 * x))


@njit(cache=True)
def rate_factor(speed: float, c: float, rl: float) -> float:
    """Y(rate) / Y = 1 + C ln(rate / rate_ref) with rate / rate_ref = speed * rl (J1);
    1 at or below the reference rate, for speed <= 0 or C = 0."""
    r = speed * rl
    if c == 0.0 or r <= 1.0:
        return 1.0
    return 1.0 + c * math.log(r)


@njit(cache=True)
def contact_scales(coef, rate: float, delta_dot: float):
    """(delta_y [m], force scale R* Y(rate) delta_y [N]) of a contact whose yield strength
    is fixed by the rate factor `rate` = Y(rate) / Y (0: not yet fixed, then the factor of
    the approach speed delta_dot)."""
    phi = rate if rate > 0.0 else rate_factor(delta_dot, coef[COEF_RC], coef[COEF_RL])
    dy = coef[COEF_DY] * phi * phi
    return dy, coef[COEF_SY] * phi * dy


@njit(cache=True)
def plastic_core(delta: float, m: float, dy: float, sf: float, h: float, kappa: float, xh: float):
    """The law past yield (m = max(delta, delta_max) > delta_y) in SI units (J4-J8): (F [N],
    dF/d delta [N/m], stored energy [J], residual overlap delta_p [m], F_max [N], the span
    delta_max - delta_p [m]); dy = delta_y [m], sf = R* Y delta_y [N]."""
    xm = m / dy
    fm, km = loading_force(xm, h, xh)
    w = unloading_span(xm, fm, kappa) * dy
    fm *= sf
    d_p = m - w
    if delta >= m:
        return fm, km * sf / dy, 0.4 * fm * w, d_p, fm, w
    u = (delta - d_p) / w
    if u <= 0.0:
        return 0.0, 0.0, 0.0, d_p, fm, w
    su = math.sqrt(u)
    f = fm * u * su
    return f, 1.5 * fm * su / w, 0.4 * f * (delta - d_p), d_p, fm, w


@njit(cache=True)
def plastic_work_of(m: float, fm: float, w: float, dy: float, sf: float, h: float, xh: float) -> float:
    """W_p [J] at largest overlap m > delta_y with F_max = fm [N] and span w [m] (J8)."""
    return loading_work(m / dy, h, xh) * sf * dy - 0.4 * fm * w


@njit(cache=True)
def johnson_state(delta: float, delta_max: float, coef, rate: float, delta_dot: float):
    """The law at overlap delta with history delta_max (J8): (F [N], dF/d delta [N/m],
    stored elastic energy [J], plastic work W_p(max(delta, delta_max)) [J], residual overlap
    delta_p [m]); an elastic history gives Hertz's force, slope and energy, W_p = delta_p = 0."""
    dy, sf = contact_scales(coef, rate, delta_dot)
    m = delta if delta > delta_max else delta_max
    if m <= dy:
        if delta <= 0.0:
            return 0.0, 0.0, 0.0, 0.0, 0.0
        a = coef[COEF_A]
        sq = math.sqrt(delta)
        return a * delta * sq, 1.5 * a * sq, 0.4 * a * delta * delta * sq, 0.0, 0.0
    h, xh = coef[COEF_H], coef[COEF_XH]
    f, k, ep, d_p, fm, w = plastic_core(delta, m, dy, sf, h, coef[COEF_KAPPA], xh)
    return f, k, ep, plastic_work_of(m, fm, w, dy, sf, h, xh), d_p


@njit(cache=True)
def johnson_plastic_work(delta_max: float, coef, rate: float) -> float:
    """W_p(delta_max) [J] (J8) of a contact whose yield strength has the rate factor `rate`."""
    return johnson_state(delta_max, delta_max, coef, rate, 0.0)[3]


@njit(cache=True, inline="always")
def johnson_normal_response(delta: float, delta_dot: float, coef, delta_max: float, rate: float, clip: bool):
    """The law of one contact in touch (delta > 0) with damping on its elastic part, as
    Thornton's (P13): |N| = F + c (delta - delta_p)^(1/4) d(delta)/dt while delta >
    delta_p. Returns (|N| [N], viscous power [W], stored energy [J], plastic work done past
    delta_max [J]), as `plastic.yielding_normal_response`."""
    c = coef[COEF_C]
    dy, sf = contact_scales(coef, rate, delta_dot)
    if delta <= dy and delta_max <= dy:  # an elastic history: Hertz, eqs. (2) and (9)
        n, pv, ep = normal_response(delta, delta_dot, coef[COEF_A], c, clip)
        return n, pv, ep, 0.0
    h, kappa, xh = coef[COEF_H], coef[COEF_KAPPA], coef[COEF_XH]
    m = delta if delta > delta_max else delta_max
    f, k, ep, d_p, fm, w = plastic_core(delta, m, dy, sf, h, kappa, xh)
    w_p = 0.0
    if delta > delta_max:  # loading past the largest overlap: the plastic work done since
        w_p = plastic_work_of(m, fm, w, dy, sf, h, xh)
        if delta_max > dy:
            f0, k0, e0, p0, fm0, w0 = plastic_core(delta_max, delta_max, dy, sf, h, kappa, xh)
            w_p -= plastic_work_of(delta_max, fm0, w0, dy, sf, h, xh)
    d_el = delta - d_p
    if d_el <= 0.0:
        return 0.0, 0.0, 0.0, w_p
    n = f + c * math.sqrt(math.sqrt(d_el)) * delta_dot
    if clip and n < 0.0:
        n = 0.0
    return n, (n - f) * delta_dot, ep, w_p


@njit(cache=True, inline="always")
def johnson_normal_force(delta: float, delta_dot: float, coef, delta_max: float, rate: float, clip: bool) -> float:
    """|N| [N] of `johnson_normal_response` alone (no energies)."""
    c = coef[COEF_C]
    dy, sf = contact_scales(coef, rate, delta_dot)
    if delta <= dy and delta_max <= dy:
        return normal_force(delta, delta_dot, coef[COEF_A], c, clip)[0]
    m = delta if delta > delta_max else delta_max
    f, k, ep, d_p, fm, w = plastic_core(delta, m, dy, sf, coef[COEF_H], coef[COEF_KAPPA], coef[COEF_XH])
    d_el = delta - d_p
    if d_el <= 0.0:
        return 0.0
    n = f + c * math.sqrt(math.sqrt(d_el)) * delta_dot
    return 0.0 if clip and n < 0.0 else n


@njit(cache=True)
def johnson_normal_slopes(delta: float, coef, delta_max: float, rate: float):
    """dN/d(delta) [N/m] and dN/d(delta rate) [N s/m] in touch (the implicit scheme's
    Newton); an unset rate factor is taken as 1."""
    f, k, ep, wp, d_p = johnson_state(delta, delta_max, coef, rate, 0.0)
    d_el = delta - d_p
    if d_el <= 0.0:
        return 0.0, 0.0
    return k, coef[COEF_C] * math.sqrt(math.sqrt(d_el))


@njit(entry=True, cache=True)
def johnson_replay(delta: np.ndarray, coef, speed: float) -> np.ndarray:
    """The law's force [N] along an overlap history delta (n,) [m] from a virgin contact,
    its yield strength fixed by the approach speed `speed` [m/s] (<= 0: rate-free; no
    damping): the measured curves' replay."""
    rate = rate_factor(speed, coef[COEF_RC], coef[COEF_RL])
    out = np.zeros(delta.shape[0])
    m = 0.0
    for i in range(delta.shape[0]):
        d = delta[i]
        if d > 0.0:
            out[i] = johnson_state(d, m, coef, rate, 0.0)[0]
        if d > m:
            m = d
    return out


# The law as a registered normal law ("johnson"; docs/architecture.md, "Adding a normal
# law"): the common arguments of physics.laws. A contact whose overlap and largest overlap
# are both at or below the rate-free yield overlap COEF_DY takes Hertz's code at once,
# without the rate factor's logarithm (the same result: the law's yield overlap at its rate
# factor is never below COEF_DY, since C >= 0).


@njit(cache=True, inline="always")
def law_response(delta: float, delta_dot: float, coef, delta_max: float, rate: float, clip: bool):
    """`johnson_normal_response`, with Hertz's code for an elastic history."""
    delta_y = coef[COEF_DY]
    if delta <= delta_y and delta_max <= delta_y:
        n, pv, ep = normal_response(delta, delta_dot, coef[COEF_A], coef[COEF_C], clip)
        return n, pv, ep, 0.0
    return johnson_normal_response(delta, delta_dot, coef, delta_max, rate, clip)


@njit(cache=True, inline="always")
def law_force(delta: float, delta_dot: float, coef, delta_max: float, rate: float, clip: bool) -> float:
    """`johnson_normal_force`, with Hertz's code for an elastic history."""
    delta_y = coef[COEF_DY]
    if delta <= delta_y and delta_max <= delta_y:
        return normal_force(delta, delta_dot, coef[COEF_A], coef[COEF_C], clip)[0]
    return johnson_normal_force(delta, delta_dot, coef, delta_max, rate, clip)


@njit(cache=True, inline="always")
def law_slopes(delta: float, coef, delta_max: float, rate: float):
    """`johnson_normal_slopes`."""
    return johnson_normal_slopes(delta, coef, delta_max, rate)


@njit(cache=True, inline="always")
def law_rate(d: float, d_old: float, t: float, t_old: float, rate: float, coef) -> float:
    """The rate factor once the largest overlap grows from d_old (reached at t_old [s]) to
    d [m] (at t [s]): fixed in the accepted step where the largest overlap first passes the
    rate-free yield overlap, from the approach speed (d - d_old) / (t - t_old) over that
    step (`rate_factor`; -1, rate-free, when the contact passed yield in its first step in
    touch); else unchanged."""
    if rate == 0.0 and d > coef[COEF_DY]:
        return rate_factor(fixing_speed(d, d_old, t, t_old), coef[COEF_RC], coef[COEF_RL])
    return rate


@njit(cache=True)
def fixing_speed(d: float, d_old: float, t: float, t_old: float) -> float:
    """The approach speed [m/s] that fixes a contact's yield strength (docs/model.md
    section 3.10): the growth of its largest overlap over the accepted step, (d - d_old) /
    (t - t_old), from its previous largest overlap d_old reached at t_old; -1 (rate-free)
    when there is none (the contact passed yield in its first step in touch)."""
    if d_old > 0.0 and t > t_old:
        return (d - d_old) / (t - t_old)
    return -1.0


def law_columns(softer, e_star: float, r_star: float, length: float) -> np.ndarray:
    """The law's columns COEF_DY..COEF_XH of a contact whose softer body is `softer` (a
    Material, its Y known), E* [Pa], R* [m], `length` [m] the length that makes the approach
    speed a strain rate: delta_y, R* Y, C, 1 / (length rate_ref), h, kappa and x_h
    (docs/model.md section 3.10; absent rate fields: rate-free)."""
    m = softer
    out = np.zeros(N_LAW_COLUMNS)
    out[0] = contact_yield_overlap(e_star, r_star, m.Y)
    out[COEF_SY - COEF_DY] = r_star * m.Y
    if m.C is not None and m.rate_ref is not None:
        out[COEF_RC - COEF_DY] = m.C
        out[COEF_RL - COEF_DY] = 1.0 / (length * m.rate_ref)
    out[COEF_H - COEF_DY] = DEFAULT_HARDNESS_RATIO if m.hardness_ratio is None else m.hardness_ratio
    out[COEF_KAPPA - COEF_DY] = DEFAULT_UNLOADING_FACTOR if m.unloading_factor is None else m.unloading_factor
    out[COEF_XH - COEF_DY] = hardness_overlap(out[COEF_H - COEF_DY])
    return out

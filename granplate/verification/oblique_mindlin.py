"""The oblique impact of an elastic sphere on a rigid flat under Mindlin's tangential law
(docs/model.md section 3.16, eqs. M1-M5, LAMMPS's `mindlin_rescale`), written here from
the equations alone: Di Renzo & Di Maio's normalised angles, the gross-sliding line and
its threshold in closed form, and `reference_impact`, an independent scipy integration of
the continuous law (docs/validation.md, "Mindlin friction on the whole oblique-impact
curve").

The sphere (radius R, mass m, inertia 2/5 m R^2, no spin before) meets the flat at the
normal speed v_n and the contact point's tangential speed v_c1. With kappa = 2 (1 - nu) /
(2 - nu), the ratio of Mindlin's tangential stiffness 8 G* a to Hertz's normal one 2 E* a,

    Psi = v_c / (kappa^-1 mu v_n) = 2 (1 - nu) / (mu (2 - nu)) v_c / v_n            (O1)

(Maw, Barber & Fawcett 1976, Di Renzo & Di Maio 2004: Psi1 of the incidence, Psi2 of the
rebound, both over the incident v_n). The normal impact is Hertz's and elastic; the
tangential force F acts on the contact point, whose speed changes by 7/2 F / m (1/m +
R^2 / I). The continuous law the integrator runs (the time-step limit of eqs. M2-M5,
undamped, the normal fixed):

    stick:  xi' = v_c + xi min(a'/a, 0),  F = -k_t xi,  k_t = 8 G* a,  a = sqrt(R delta)  (O2)
    slip:   F = -s mu N,  xi = s mu N / k_t = s c delta,  c = mu E* / (6 G*) = 2 mu / (3 kappa)  (O3)

A stuck contact slips when k_t |xi| reaches mu N; a slipping one sticks when the spring
would fall below the cap, s (v_c + xi min(a'/a, 0)) < d(c delta)/dt: s v_c < c delta' while
loading, s v_c < c delta' / 2 while unloading (the rescale of M2 takes xi down with a).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from .impact_theory import HERTZ_TIME_CONSTANT

#: Source line of the independent integration.
REFERENCE_SOURCE = (
    "scipy DOP853 of the continuous law (Hertz, Mindlin's spring 8 G* a rescaled with a, Coulomb's cap; "
    "stick and slip switched at located events), rtol 1e-12, written independently"
)

#: The contact point's speed changes by SPIN_FACTOR F / m under a tangential force F on a
#: solid sphere: 1 + m R^2 / I with I = 2/5 m R^2.
SPIN_FACTOR = 3.5


def stiffness_ratio(nu: float) -> float:
    """kappa = 8 G* / (2 E*) = 2 (1 - nu) / (2 - nu) [-] for a sphere on a rigid flat or two
    equal spheres of Poisson's ratio nu (Mindlin 1949)."""
    return 2.0 * (1.0 - nu) / (2.0 - nu)


def normalised_angle(v_c: float, v_n: float, mu: float, nu: float) -> float:
    """Psi = 2 (1 - nu) / (mu (2 - nu)) v_c / v_n [-] (eq. O1): v_c the contact point's
    tangential speed, v_n the incident normal speed [m/s]."""
    return stiffness_ratio(nu) * v_c / (mu * v_n)


def sliding_line(psi1, nu: float, restitution: float = 1.0):
    """Psi2 in gross sliding: the tangential impulse is mu times the normal one, (1 + e) m
    v_n, so v_c2 = v_c1 - (1 + e) (1 + m R^2 / I) mu v_n = v_c1 - 7 mu v_n for e = 1, and
    Psi2 = Psi1 - (1 + e) (7/2) kappa = Psi1 - 7 kappa (= Psi1 - 4 chi in Maw, Barber &
    Fawcett's chi = (1 - nu)/(2 - nu) (1 + m R^2 / I))."""
    return np.asarray(psi1) - (1.0 + restitution) * SPIN_FACTOR * stiffness_ratio(nu)


def sliding_threshold(nu: float) -> float:
    """The smallest Psi1 at which the contact of eqs. (O2)-(O3) slides throughout [-]:
    7 kappa - 1/3. In sliding v_c = v_c1 - 7/2 mu (v_n - delta'); it stays above c delta'
    while loading (tightest at delta' = 0: Psi1 >= 7/2 kappa) and above c delta' / 2 while
    unloading (tightest at the end, delta' = -v_n: v_c1 >= 7 mu v_n - c v_n / 2), the
    latter binding for kappa > 2/21: Psi1 >= 7 kappa - 1/3, where Psi2 = -1/3."""
    return 7.0 * stiffness_ratio(nu) - 1.0 / 3.0


def slip_onset() -> float:
    """Psi1 below which the contact sticks at first touch [-]: 2/3 (xi = v_c1 t with k_t
    ~ t^(1/2) against mu N ~ t^(3/2): k_t xi / (mu N) -> 3/2 Psi1 as t -> 0)."""
    return 2.0 / 3.0


@dataclass(frozen=True)
class Rebound:
    """The sphere after the impact: its normal and tangential (centre) speeds v_n2, v_t2
    [m/s] (v_n2 > 0 away from the flat), its spin omega2 [rad/s] (positive rolling the
    way it moves), the contact point's speed v_c2 [m/s], Psi2 (eq. O1 over the incident
    v_n), the tangential restitution e_t = -v_c2 / v_c1 and the contact time t_c [s]."""

    v_n2: float
    v_t2: float
    omega2: float
    v_c2: float
    psi2: float
    e_t: float
    t_c: float


def impact_constants(radius: float, young: float, nu: float, rho: float, mu: float) -> dict:
    """Mass m [kg], Hertz's A = 4/3 E* sqrt(R) [N m^-3/2], 8 G* sqrt(R) [N m^-3/2] (k_t =
    that sqrt(delta)) and c = mu E* / (6 G*) [-] of a sphere on a rigid flat, from the
    material constants (1/E* = (1 - nu^2)/E, 1/G* = (2 - nu)/G, G = E / (2 (1 + nu)))."""
    e_star = young / (1.0 - nu * nu)
    g_star = young / (2.0 * (1.0 + nu)) / (2.0 - nu)
    return {
        "m": 4.0 / 3.0 * math.pi * radius**3 * rho,
        "A": 4.0 / 3.0 * e_star * math.sqrt(radius),
        "K": 8.0 * g_star * math.sqrt(radius),
        "c": mu * e_star / (6.0 * g_star),
        "mu": mu,
        "R": radius,
    }


def _rhs(k: dict, v_c1: float, stick: bool, s: float):
    """d/dt of (delta, delta', J[, xi]) in one regime: J the tangential impulse [N s]."""
    m, a_h, k_t, mu = k["m"], k["A"], k["K"], k["mu"]

    def rhs(_t, y):
        d = max(y[0], 0.0)
        n = a_h * d**1.5
        v_c = v_c1 + SPIN_FACTOR * y[2] / m
        if stick:
            shrink = min(y[1] / (2.0 * d), 0.0) if d > 0.0 else 0.0
            return [y[1], -n / m, -k_t * math.sqrt(d) * y[3], v_c + y[3] * shrink]
        return [y[1], -n / m, -s * mu * n]

    return rhs


def _events(k: dict, v_c1: float, stick: bool, s: float) -> list:
    """The regime's end (terminal events): the contact opens; stick -> slip at k_t |xi| =
    mu N; slip -> stick where s v_c falls below c delta' (loading) or c delta' / 2."""
    m, a_h, k_t, mu, c = k["m"], k["A"], k["K"], k["mu"], k["c"]

    def opens(_t, y):
        return y[0]

    def slips(_t, y):
        d = max(y[0], 0.0)
        return k_t * math.sqrt(d) * abs(y[3]) - mu * a_h * d**1.5

    def sticks(_t, y):
        v_c = v_c1 + SPIN_FACTOR * y[2] / m
        return s * v_c - c * (y[1] if y[1] > 0.0 else 0.5 * y[1])

    opens.terminal, opens.direction = True, -1.0  # type: ignore[attr-defined]
    slips.terminal, slips.direction = True, 1.0  # type: ignore[attr-defined]
    sticks.terminal, sticks.direction = True, -1.0  # type: ignore[attr-defined]
    return [opens, slips] if stick else [opens, sticks]


def reference_impact(
    v_n: float, v_c1: float, radius: float, young: float, nu: float, rho: float, mu: float, rtol: float = 1e-12
) -> Rebound:
    """The sphere's rebound from a rigid flat under eqs. (O2)-(O3), integrated by scipy's
    DOP853 regime by regime, each switch located as an event (a regime that starts at its
    own switching point is stepped off it by the sign its rate takes). v_n, v_c1 [m/s]:
    incident normal and contact-point tangential speeds (no spin); radius [m], young [Pa],
    rho [kg/m^3]."""
    k = impact_constants(radius, young, nu, rho, mu)
    m = k["m"]
    t_c = HERTZ_TIME_CONSTANT * (15.0 * m * v_n**2 / (16.0 * k["A"])) ** 0.4 / v_n
    y = np.array([0.0, v_n, 0.0])
    stick = normalised_angle(abs(v_c1), v_n, mu, nu) < slip_onset()
    s = math.copysign(1.0, v_c1)
    xi = 0.0
    t = 0.0
    scale = np.array([(m * v_n**2 / k["A"]) ** 0.4, v_n, m * v_n, (m * v_n**2 / k["A"]) ** 0.4])
    for _ in range(50):
        state = np.append(y, xi) if stick else y
        sol = solve_ivp(
            _rhs(k, v_c1, stick, s),
            (t, t + 3.0 * t_c),
            state,
            method="DOP853",
            rtol=rtol,
            atol=rtol * 1e-3 * scale[: len(state)],
            events=_events(k, v_c1, stick, s),
        )
        hit = [len(e) > 0 for e in sol.t_events]
        if not any(hit):
            raise RuntimeError(f"reference_impact: the contact did not open within {3.0 * t_c:g} s")
        t = float(sol.t[-1])
        end = sol.y[:, -1]
        if hit[0]:
            y = end[:3]
            break
        y = end[:3]
        if stick:
            s = math.copysign(1.0, end[3])
            stick = False
        else:
            xi = s * k["c"] * y[0]
            stick = True
    else:
        raise RuntimeError("reference_impact: more than 50 stick-slip switches")
    j = float(y[2])
    v_c2 = v_c1 + SPIN_FACTOR * j / m
    return Rebound(
        v_n2=float(-y[1]),
        v_t2=v_c1 + j / m,
        omega2=-(SPIN_FACTOR - 1.0) * j / (m * radius),
        v_c2=v_c2,
        psi2=normalised_angle(v_c2, v_n, mu, nu),
        e_t=-v_c2 / v_c1,
        t_c=t,
    )

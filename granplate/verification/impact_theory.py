"""Reference solutions for sphere impacts (docs/model.md section 4.6).

- Hertz's impact of a sphere on a rigid flat or an elastic half-space (Johnson, Contact
  Mechanics, 1985, section 11.4): the largest overlap, the contact time, the peak force,
  and `hertz_impact`, an independent scipy integration of m x'' = -(4/3) E* sqrt(R) x^(3/2);
- Zener's impact of a sphere on a large thin plate (C. Zener, Phys. Rev. 59, 669, 1941):
  the infinite Kirchhoff plate answers a point force F with the velocity F / (8 sqrt(D rho h))
  (its driving-point mobility, real: a dashpot), Hertz's contact in series with it;
  `zener_impact` integrates the model in its non-dimensional form, in which the one
  parameter is Zener's inelasticity lambda, and `zener_impact_si` the same model in SI;
- the elastic waves a sphere's impact sends into a half-space (`hunter_radiated_fraction`,
  Hunter 1957): the share of the impact's energy they take away;
- the flexural waves that carry the plate's energy away, and the time their reflection
  from an edge of a finite plate returns to the contact (`reflection_time`), the time up to
  which a finite plate behaves as Zener's infinite one.

Zener's own curve e(lambda) is a figure; its points are not reproduced here. What the
tests hold the integration to is exact: the energy balance of the model, e -> 1 as
lambda -> 0, and the first-order loss 1 - e^2 = c lambda with c from the rigid impact
in closed form (`zener_first_order_loss`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from scipy.integrate import solve_ivp
from scipy.special import beta as beta_function

#: t_c = HERTZ_TIME_CONSTANT delta_max / v0: 2 int_0^1 dx / sqrt(1 - x^(5/2)) = (4/5) B(2/5, 1/2)
#: = 2.9432 (Johnson 1985, section 11.4, rounds it to 2.94).
HERTZ_TIME_CONSTANT = 0.8 * float(beta_function(0.4, 0.5))


# --------------------------------------------------------------------------- Hertz


def effective_modulus(young_1: float, poisson_1: float, young_2: float = math.inf, poisson_2: float = 0.0) -> float:
    """E* [Pa]: 1 / E* = (1 - nu1^2) / E1 + (1 - nu2^2) / E2 (Johnson 1985, section 4.2);
    E2 = inf: a rigid flat."""
    second = 0.0 if math.isinf(young_2) else (1.0 - poisson_2**2) / young_2
    return 1.0 / ((1.0 - poisson_1**2) / young_1 + second)


def hertz_stiffness(e_star: float, radius: float) -> float:
    """k = (4/3) E* sqrt(R) [N m^-3/2]: F = k delta^(3/2) (Johnson 1985, section 4.2)."""
    return 4.0 / 3.0 * e_star * math.sqrt(radius)


def hertz_max_overlap(mass: float, speed: float, e_star: float, radius: float) -> float:
    """delta_max = (15 m v0^2 / (16 E* sqrt(R)))^(2/5) [m] (Johnson 1985, section 11.4), m the
    reduced mass of the pair, v0 the relative approach speed."""
    return (15.0 * mass * speed**2 / (16.0 * e_star * math.sqrt(radius))) ** 0.4


def hertz_contact_time(mass: float, speed: float, e_star: float, radius: float) -> float:
    """t_c = 2.9432 delta_max / v0 [s] (Johnson 1985, section 11.4: 2.94 delta_max / v0)."""
    return HERTZ_TIME_CONSTANT * hertz_max_overlap(mass, speed, e_star, radius) / speed


def hertz_peak_force(mass: float, speed: float, e_star: float, radius: float) -> float:
    """F_max = (4/3) E* sqrt(R) delta_max^(3/2) [N], at the largest overlap."""
    return hertz_stiffness(e_star, radius) * hertz_max_overlap(mass, speed, e_star, radius) ** 1.5


def hunter_radiated_fraction(speed: float, young: float, rho: float) -> float:
    """W / (m v0^2 / 2) = 1.04 (v0 / c0)^(3/5), c0 = sqrt(E / rho): the share of a sphere's
    kinetic energy that the elastic waves radiated into a half-space carry away in a
    Hertzian impact (S. C. Hunter, J. Mech. Phys. Solids 5, 162, 1957, for a steel sphere
    on a thick steel body; the coefficient as Johnson 1985, section 11.4, quotes it, the
    paper itself not at hand). Small: 1 - e^2 of a wave-radiation loss alone.
    """
    return 1.04 * (speed / math.sqrt(young / rho)) ** 0.6


class HertzImpact(NamedTuple):
    """An integrated elastic impact: contact time [s], largest overlap [m], peak force [N],
    rebound speed [m/s]."""

    contact_time: float
    max_overlap: float
    peak_force: float
    rebound_speed: float


def hertz_impact(mass: float, speed: float, e_star: float, radius: float, rtol: float = 1e-11) -> HertzImpact:
    """m x'' = -(4/3) E* sqrt(R) x^(3/2) from x = 0, x' = v0, integrated (scipy DOP853) up
    to x = 0 again: independent of the closed forms above."""
    k = hertz_stiffness(e_star, radius)
    scale_t = hertz_max_overlap(mass, speed, e_star, radius) / speed

    def rhs(_t, s):
        return [s[1], -k * max(s[0], 0.0) ** 1.5 / mass]

    def separated(_t, s):
        return s[0]

    separated.terminal, separated.direction = True, -1.0
    sol = solve_ivp(
        rhs,
        (0.0, 10.0 * scale_t),
        [0.0, speed],
        method="DOP853",
        rtol=rtol,
        atol=[1e-14 * speed * scale_t, 1e-14 * speed],
        events=separated,
        dense_output=True,
    )
    t_c = float(sol.t_events[0][0])
    times = np.linspace(0.0, t_c, 2001)
    x_max = float(np.max(sol.sol(times)[0]))
    return HertzImpact(t_c, x_max, k * x_max**1.5, float(-sol.y_events[0][0][1]))


# --------------------------------------------------------------------------- Zener's thin plate


def plate_point_mobility(rigidity: float, rho: float, thickness: float) -> float:
    """Y = 1 / (8 sqrt(D rho h)) [m / (N s)]: the velocity of an infinite thin plate at a
    point force, per unit force; real, so the plate is a dashpot there (Zener 1941;
    Cremer, Heckl & Petersson, Structure-Borne Sound, the infinite plate's point mobility)."""
    return 1.0 / (8.0 * math.sqrt(rigidity * rho * thickness))


def zener_inelasticity(mass: float, speed: float, stiffness: float, mobility: float) -> float:
    """Zener's lambda = k^(2/5) m^(3/5) v0^(1/5) Y (dimensionless): with the overlap in
    units of (m v0^2 / k)^(2/5) and time in units of that over v0, the model
    m y'' = -F, F = k (y - w)^(3/2), w' = Y F reads s'' = -s^(3/2) - lambda d(s^(3/2))/dtau."""
    return stiffness**0.4 * mass**0.6 * speed**0.2 * mobility


def zener_inelasticity_sphere(
    radius: float,
    rho_sphere: float,
    e_star: float,
    speed: float,
    thickness: float,
    young_plate: float,
    poisson_plate: float,
    rho_plate: float,
) -> float:
    """lambda of a solid sphere on a plate, written out from `zener_inelasticity`:
    lambda = pi^(3/5) / sqrt(3) (R / H)^2 (v0 / c)^(1/5) (rho_s / rho_p)^(3/5)
    (E* / E_p)^(2/5) sqrt(1 - nu_p^2), H the plate's thickness, c = sqrt(E_p / rho_p).
    In Zener's notation (1941) the plate is 2h thick, so (R / H)^2 reads (R / 2h)^2; the
    material factors are derived here from the model's equations, not copied."""
    c = math.sqrt(young_plate / rho_plate)
    return (
        math.pi**0.6
        / math.sqrt(3.0)
        * (radius / thickness) ** 2
        * (speed / c) ** 0.2
        * (rho_sphere / rho_plate) ** 0.6
        * (e_star / young_plate) ** 0.4
        * math.sqrt(1.0 - poisson_plate**2)
    )


def zener_scales(mass: float, speed: float, stiffness: float) -> tuple[float, float]:
    """(time [s], force [N]) units of `zener_impact`'s non-dimensional results: the overlap
    unit (m v0^2 / k)^(2/5) over v0, and k times that unit^(3/2)."""
    overlap = (mass * speed**2 / stiffness) ** 0.4
    return overlap / speed, stiffness * overlap**1.5


def zener_first_order_loss() -> float:
    """c in 1 - e^2 = c lambda + O(lambda^2): the energy the dashpot takes from the rigid
    Hertz impact, 2 lambda int s^3 dtau with s'^2 = 1 - (4/5) s^(5/2), which is
    (8/5) (5/4)^(8/5) B(8/5, 1/2) = 3.460."""
    return 1.6 * 1.25**1.6 * float(beta_function(1.6, 0.5))


class ZenerImpact(NamedTuple):
    """Zener's impact in non-dimensional units (overlap (m v0^2/k)^(2/5), time that over v0,
    energy m v0^2): restitution e, contact time, peak force s^(3/2), and the trajectory
    (tau, overlap s, sphere velocity u, dissipated energy) at the integrator's steps."""

    restitution: float
    contact_time: float
    peak_force: float
    tau: np.ndarray
    overlap: np.ndarray
    velocity: np.ndarray
    dissipated: np.ndarray


def zener_impact(inelasticity: float, rtol: float = 1e-10) -> ZenerImpact:
    """Zener's model, non-dimensional: u' = -s^(3/2) (the sphere), s' = u - lambda s^(3/2)
    (the overlap: the sphere's velocity less the plate's, lambda s^(3/2)), the dashpot's
    dissipation d' = lambda s^3; from s = 0, u = 1 up to s = 0 again, e = -u there (the
    plate, a dashpot, stops with the force, so the sphere leaves at -u for good)."""
    lam = float(inelasticity)
    if not lam >= 0.0:
        raise ValueError(f"the inelasticity must be >= 0, not {inelasticity!r}")

    def rhs(_t, y):
        f = max(y[0], 0.0) ** 1.5
        return [y[1] - lam * f, -f, lam * f * f]

    def separated(_t, y):
        return y[0]

    separated.terminal, separated.direction = True, -1.0

    def deepest(_t, y):  # s' = 0: the largest overlap, where the force peaks
        return y[1] - lam * max(y[0], 0.0) ** 1.5

    deepest.direction = -1.0
    sol = solve_ivp(
        rhs,
        (0.0, 50.0 + 20.0 * lam),
        [0.0, 1.0, 0.0],
        method="DOP853",
        rtol=rtol,
        atol=1e-13,
        events=(separated, deepest),
    )
    if not sol.t_events[0].size:
        raise RuntimeError(f"no separation found for lambda = {lam}")
    tau, y = sol.t, sol.y
    return ZenerImpact(
        float(-sol.y_events[0][0][1]),
        float(sol.t_events[0][0]),
        float(sol.y_events[1][0][0]) ** 1.5,
        tau,
        y[0],
        y[1],
        y[2],
    )


def zener_restitution(inelasticity: float) -> float:
    """e(lambda) of Zener's model (`zener_impact`)."""
    return zener_impact(inelasticity).restitution


def zener_energy(impact: ZenerImpact) -> np.ndarray:
    """Kinetic + Hertz + dissipated energy along an impact, u^2/2 + (2/5) s^(5/2) + d, in
    units of m v0^2: 1/2 at every step for an exact integration."""
    return 0.5 * impact.velocity**2 + 0.4 * np.maximum(impact.overlap, 0.0) ** 2.5 + impact.dissipated


def zener_impact_si(mass: float, speed: float, stiffness: float, mobility: float, rtol: float = 1e-10) -> float:
    """The restitution of Zener's model integrated in SI units: m y'' = -F,
    F = k (y - w)^(3/2), w' = Y F (y the sphere's and w the plate's displacement [m])."""
    t_scale = (mass * speed**2 / stiffness) ** 0.4 / speed

    def rhs(_t, s):
        f = stiffness * max(s[0] - s[2], 0.0) ** 1.5
        return [s[1], -f / mass, mobility * f]

    def separated(_t, s):
        return s[0] - s[2]

    separated.terminal, separated.direction = True, -1.0
    sol = solve_ivp(
        rhs,
        (0.0, 200.0 * t_scale),
        [0.0, speed, 0.0],
        method="DOP853",
        rtol=rtol,
        atol=[1e-14 * speed * t_scale, 1e-14 * speed, 1e-14 * speed * t_scale],
        events=separated,
    )
    return float(-sol.y_events[0][0][1] / speed)


# --------------------------------------------------------------------------- flexural waves


def flexural_phase_velocity(omega: float, rigidity: float, rho: float, thickness: float) -> float:
    """c = sqrt(omega) (D / (rho h))^(1/4) [m/s]: omega = k^2 sqrt(D / (rho h)) for a
    Kirchhoff plate (Graff, Wave Motion in Elastic Solids, 1975, section 4.2)."""
    return math.sqrt(omega) * (rigidity / (rho * thickness)) ** 0.25


def flexural_group_velocity(omega: float, rigidity: float, rho: float, thickness: float) -> float:
    """c_g = d omega / dk = 2 sqrt(omega) (D / (rho h))^(1/4) [m/s], twice the phase velocity."""
    return 2.0 * flexural_phase_velocity(omega, rigidity, rho, thickness)


def hertz_pulse_frequency(contact_time: float) -> float:
    """omega_c = pi / t_c [rad/s]: a contact force lasting t_c is half a period of it.
    Components above omega_c travel faster (c_g ~ sqrt(omega)): a bound on the return
    time wants the highest frequency that matters, e.g. a few omega_c."""
    return math.pi / contact_time


def reflection_time(distance: float, omega: float, rigidity: float, rho: float, thickness: float) -> float:
    """t_r = 2 L / c_g(omega) [s]: when the flexural wave of frequency omega sent out at the
    contact is back from an edge at distance L; before it, a finite plate answers the
    contact as Zener's infinite one."""
    return 2.0 * distance / flexural_group_velocity(omega, rigidity, rho, thickness)

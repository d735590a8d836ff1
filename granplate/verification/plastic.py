"""References for contacts beyond the elastic limit (docs/model.md section 3.6).

Thornton's elastic-perfectly plastic law (Thornton 1997, J. Appl. Mech. 64, 383) as
closed forms, and an independent integration of a head-on impact with it, written here
in Thornton's own variables (E*, R*, p_y, R_p), not with `granplate.physics.plastic`:

- `thornton_yield_velocity` (P11) and `johnson_yield_velocity` (Johnson, Contact
  Mechanics, 1985, section 11.4: rho v_y^2 / Y = 26 (Y/E*)^4 for a sphere on a rigid flat);
- `thornton_restitution` (P12), the coefficient of restitution e(v / v_y);
- `impact`: a scipy `solve_ivp` (DOP853) of two bodies (or a body against a rigid wall)
  pressed together by the law without damping, each leg of the law integrated up to an
  event where the next one starts (yield, the largest overlap, separation), giving the
  rebound speed, the largest overlap and the residual one.

Thornton's closed form makes no approximation beyond those of the law itself (the
truncated-Hertz pressure over the disc a^2 = R* delta while loading, and Hertzian
unloading of radius R_p): e^2 is U(delta_max) / (1/2 m* v^2), so the integration and
P12 agree to the integrator's tolerance. These are functions with tests
(tests/test_plastic_verification.py); the case `plastic-impact` (plastic_cases.py) holds
the time loop's yielding impacts against them.
"""

from __future__ import annotations

import math

from scipy.integrate import solve_ivp

#: Johnson's constant: rho v_y^2 / Y = JOHNSON_YIELD (Y / E*)^4 (sphere on a rigid flat).
JOHNSON_YIELD = 26.0


# --------------------------------------------------------------------------- closed forms


def yield_overlap(e_star: float, r_star: float, p_y: float) -> float:
    """delta_y = (pi p_y / (2 E*))^2 R* [m]: the overlap where Hertz's p0 reaches p_y."""
    return (math.pi * p_y / (2.0 * e_star)) ** 2 * r_star


def thornton_yield_velocity(e_star: float, r_star: float, m_star: float, p_y: float) -> float:
    """v_y = (pi / (2 E*))^2 sqrt(8 pi R*^3 p_y^5 / (15 m*)) [m/s] (P11): the relative
    impact speed whose Hertz contact just reaches p0 = p_y."""
    return (math.pi / (2.0 * e_star)) ** 2 * math.sqrt(8.0 * math.pi * r_star**3 * p_y**5 / (15.0 * m_star))


def johnson_yield_velocity(e_star: float, rho: float, y_strength: float) -> float:
    """v_y = sqrt(26 (Y/E*)^4 Y / rho) [m/s]: Johnson's yield velocity of a sphere of
    density rho on a rigid flat (p0 = 1.6 Y at yield; 26 rounds the exact 25.5)."""
    return math.sqrt(JOHNSON_YIELD * (y_strength / e_star) ** 4 * y_strength / rho)


def thornton_restitution(speed_ratio: float) -> float:
    """Thornton's coefficient of restitution e (P12) at impact speed v = speed_ratio v_y:
    (6 sqrt3 / 5)^(1/2) (1 - r^2/6)^(1/2) (r / (r + 2 sqrt(6/5 - r^2/5)))^(1/4) with
    r = v_y / v; 1 (elastic) for v <= v_y."""
    if speed_ratio <= 1.0:
        return 1.0
    r = 1.0 / speed_ratio
    return (
        math.sqrt(6.0 * math.sqrt(3.0) / 5.0)
        * math.sqrt(1.0 - r * r / 6.0)
        * (r / (r + 2.0 * math.sqrt(6.0 / 5.0 - r * r / 5.0))) ** 0.25
    )


# --------------------------------------------------------------------------- the law, Thornton's variables


def _hertz(e_star: float, radius: float, delta: float) -> float:
    """Hertz's force 4/3 E* sqrt(R) delta^(3/2) [N] of radius R; 0 for delta <= 0."""
    return 4.0 / 3.0 * e_star * math.sqrt(radius) * max(delta, 0.0) ** 1.5


def _unloading(e_star: float, r_star: float, p_y: float, delta_max: float) -> tuple[float, float]:
    """(R_p, delta_p) of the unloading curve from delta_max > delta_y (Thornton 1997):
    F_max from the loading line, R_p = 4E*/(3F_max) ((2F_max + F_y)/(2 pi p_y))^(3/2),
    delta_p from F_max = 4/3 E* sqrt(R_p) (delta_max - delta_p)^(3/2)."""
    d_y = yield_overlap(e_star, r_star, p_y)
    f_y = math.pi**3 * p_y**3 * r_star**2 / (6.0 * e_star**2)
    f_max = f_y + math.pi * p_y * r_star * (delta_max - d_y)
    r_p = 4.0 * e_star / (3.0 * f_max) * ((2.0 * f_max + f_y) / (2.0 * math.pi * p_y)) ** 1.5
    d_p = delta_max - (3.0 * f_max / (4.0 * e_star * math.sqrt(r_p))) ** (2.0 / 3.0)
    return r_p, d_p


# --------------------------------------------------------------------------- the impact


def impact(m1: float, m2: float, e_star: float, r_star: float, p_y: float, v: float, rtol: float = 1e-12) -> dict:
    """Head-on impact at relative speed v [m/s] of body 1 (mass m1) on body 2 (mass m2;
    math.inf: a rigid wall), both free, the contact (E*, R*, p_y) following Thornton's law
    without damping; integrated body by body (positions x1, x2, velocities v1, v2) with
    scipy DOP853 over three legs: Hertz up to delta_y, the loading line up to the largest
    overlap (v1 = v2), the Hertz curve of radius R_p down to delta_p (separation).

    Returns e (rebound / approach speed), delta_max, delta_p, R_p [m], the time in contact
    t_c [s], and the bodies' kinetic energy before and after [J]; plastic: whether it yielded.
    """
    wall = math.isinf(m2)
    d_y = yield_overlap(e_star, r_star, p_y)

    def rhs(force):
        def f(_t, z):
            x1, v1, x2, v2 = z
            n = force(x1 - x2)  # overlap: body 1 moves +x into body 2
            return [v1, -n / m1, v2, 0.0 if wall else n / m2]

        return f

    def run(force, z0, events, scale, max_step=math.inf):
        for ev in events:
            ev.terminal = True
        t_end = 1e3 * scale / v
        atol = [1e-14 * scale, 1e-14 * v] * 2
        sol = solve_ivp(
            rhs(force), (0.0, t_end), z0, method="DOP853", rtol=rtol, atol=atol, events=events, max_step=max_step
        )
        if sol.status != 1:
            raise RuntimeError(f"impact: a leg ended without its event ({sol.message})")
        hit = next(k for k, te in enumerate(sol.t_events) if len(te))
        return list(sol.y_events[hit][0]), float(sol.t_events[hit][0]), hit

    def hertz(delta):
        return _hertz(e_star, r_star, delta)

    def approach_ends(_t, z):  # largest overlap: the relative velocity turns
        return z[1] - z[3]

    approach_ends.direction = -1

    def yields(_t, z):
        return (z[0] - z[2]) - d_y

    yields.direction = 1

    # 1: Hertz until yield or the largest overlap; short steps so that an overlap just
    # grazing delta_y (v barely above v_y) is not stepped over by the event detection
    v1, v2 = (v, 0.0) if wall else (v * m2 / (m1 + m2), -v * m1 / (m1 + m2))
    z0 = [0.0, v1, 0.0, v2]
    ke0 = 0.5 * m1 * v1**2 + (0.0 if wall else 0.5 * m2 * v2**2)
    z, t, hit = run(hertz, z0, [approach_ends, yields], d_y, max_step=1e-3 * d_y / v)
    plastic = hit == 1
    r_p, d_p = r_star, 0.0
    if plastic:
        # 2: the loading line F_y + pi p_y R* (delta - delta_y) until the largest overlap
        f_y = math.pi**3 * p_y**3 * r_star**2 / (6.0 * e_star**2)
        k_p = math.pi * p_y * r_star
        z, t2, _ = run(lambda d: f_y + k_p * (d - d_y), z, [approach_ends], d_y)
        t += t2
        r_p, d_p = _unloading(e_star, r_star, p_y, z[0] - z[2])
    delta_max = z[0] - z[2]

    # 3: elastic unloading, Hertz of radius R_p from delta_p, until the force vanishes
    def separates(_t, z):
        return (z[0] - z[2]) - d_p

    separates.direction = -1
    z, t3, _ = run(lambda d: _hertz(e_star, r_p, d - d_p), z, [separates], delta_max)
    t += t3
    ke1 = 0.5 * m1 * z[1] ** 2 + (0.0 if wall else 0.5 * m2 * z[3] ** 2)
    return {
        "e": (z[3] - z[1]) / v,
        "delta_max": delta_max,
        "delta_p": d_p,
        "R_p": r_p,
        "t_c": t,
        "kinetic_before": ke0,
        "kinetic_after": ke1,
        "plastic": plastic,
    }

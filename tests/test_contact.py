"""Contact laws (paper eqs. 2-6) against Hertz's closed forms and the damping law's
restitution; the compiled functions are the ones the time loop uses."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.special import gamma as G

from granplate.physics import contact as C
from granplate.setup.materials import LIBRARY, effective_modulus, sphere_mass
from granplate.results.run import simulate

from conftest import two_spheres

# int_0^1 dx / sqrt(1 - x^(5/2)) = (2/5) B(2/5, 1/2): Hertz contact-time constant
HERTZ_I = 0.4 * G(0.4) * G(0.5) / G(0.9)


def hertz_closed_form(v_rel: float, m_star: float, r_star: float, e_star: float):
    """(peak overlap [m], peak force [N], contact time [s]) of an elastic Hertz impact."""
    a = 4.0 / 3.0 * e_star * math.sqrt(r_star)
    d_m = (5.0 * m_star * v_rel**2 / (4.0 * a)) ** 0.4
    return d_m, a * d_m**1.5, 2.0 * HERTZ_I * d_m / v_rel


def test_normal_force_never_pulls():
    """A fast separation would make eq. (2) tensile: the force is clipped at zero, and the
    dissipated power stays exact and non-negative; clip=False is the paper's raw law."""
    n, el = C.normal_force(1e-6, -10.0, 3e10, 1e5, True)
    assert n == 0.0 and el > 0
    assert C.viscous_power(n, el, -10.0) > 0
    n_raw, _ = C.normal_force(1e-6, -10.0, 3e10, 1e5, False)
    assert n_raw < 0


def test_friction_opposes_slip_and_dissipates():
    """tanh-Coulomb friction (eq. 5): odd in the slip rate, bounded by mu |N|, power >= 0."""
    for vt in (-1.0, -1e-4, 1e-4, 1.0):
        f = C.friction_magnitude(10.0, vt, 0.1, 1000.0)
        assert abs(f) <= 1.0 + 1e-15
        assert np.sign(f) == np.sign(vt)
        assert C.friction_power(f, vt) >= 0.0
    assert C.friction_magnitude(10.0, 1.0, 0.1, 1000.0) == pytest.approx(1.0, rel=1e-12)


def test_force_is_gradient_of_contact_energy():
    """The elastic force A delta^(3/2) is the derivative of 2/5 A delta^(5/2) (eq. 9)."""
    a = 2.9e10
    for d in (1e-7, 1e-6, 3e-5):
        h = d * 1e-6
        num = (C.contact_energy(d + h, a) - C.contact_energy(d - h, a)) / (2 * h)
        assert num == pytest.approx(C.hertz_elastic(d, a), rel=1e-8)


@pytest.mark.parametrize("v", [0.1, 1.0])
def test_two_sphere_hertz_impact(v):
    """Two steel spheres, head-on, elastic: peak overlap, peak force and contact time
    against Hertz's closed forms (time step 1e-8 s, output 1e-7 s, crossings interpolated)."""
    R = 0.01
    steel = LIBRARY["steel"]
    m = sphere_mass(R, steel.rho)
    d_m, f_m, t_c = hertz_closed_form(2 * v, m / 2, R / 2, effective_modulus(steel, steel))
    ds = simulate(two_spheres(v, t_end=1.3 * t_c, out=t_c / 2000), progress=False)
    t = ds.time.values
    overlap = 2 * R - (ds.x.values[:, 1] - ds.x.values[:, 0])
    assert overlap.max() == pytest.approx(d_m, rel=2e-5)
    a_hz = 4.0 / 3.0 * effective_modulus(steel, steel) * math.sqrt(R / 2)
    assert a_hz * overlap.max() ** 1.5 == pytest.approx(f_m, rel=3e-5)
    k = np.flatnonzero(overlap[1:] <= 0)[0] + 1  # first sample after separation
    t_sep = t[k - 1] + (t[k] - t[k - 1]) * overlap[k - 1] / (overlap[k - 1] - overlap[k])
    assert t_sep == pytest.approx(t_c, rel=1e-4)
    # elastic: velocities exchanged exactly, energy conserved
    assert ds.vx.values[-1] == pytest.approx([-v, v], rel=1e-6)
    assert abs(ds.energy_residual).max() < 1e-8


def restitution(alpha_n: float, v: float) -> float:
    """Coefficient of restitution of a simulated head-on impact of two steel spheres."""
    R, steel = 0.01, LIBRARY["steel"]
    m = sphere_mass(R, steel.rho)
    _, _, t_c = hertz_closed_form(2 * v, m / 2, R / 2, effective_modulus(steel, steel))
    ds = simulate(two_spheres(v, alpha_n=alpha_n, t_end=1.5 * t_c, out=t_c / 50, dt=t_c / 5000), progress=False)
    vx = ds.vx.values[-1]
    assert abs(ds.energy_residual).max() < 1e-6
    return (vx[1] - vx[0]) / (2 * v)


def restitution_ode(alpha_n: float) -> float:
    """e from an independent high-accuracy solve of the 1-DOF collision ODE in scaled
    variables (delta = x delta_m, t = s delta_m / v): x'' = -(5/4) x^(3/2) - alpha_n
    sqrt(5/4) x^(1/4) x', x(0) = 0, x'(0) = 1, force clipped at zero."""
    from scipy.integrate import solve_ivp

    k = 1.25
    c = alpha_n * math.sqrt(k)

    def rhs(_, z):
        x, v = z
        xp = max(x, 0.0)
        f = k * xp**1.5 + c * xp**0.25 * v
        return [v, -max(f, 0.0)]

    def sep(_, z):
        return z[0]

    sep.terminal, sep.direction = True, -1
    sol = solve_ivp(rhs, (0.0, 10.0), [1e-300, 1.0], events=sep, rtol=1e-12, atol=1e-14, first_step=1e-6)
    return -sol.y_events[0][0][1]


@pytest.mark.parametrize("alpha_n", [6.313e-3, 6.313e-2])
def test_restitution_of_damping_law(alpha_n):
    """e of the law gamma = alpha_n sqrt(m* A) delta^(1/4) matches an independent ODE
    solve and does not depend on the impact speed (exact by scaling)."""
    e1 = restitution(alpha_n, 0.05)
    e2 = restitution(alpha_n, 1.0)
    assert e1 == pytest.approx(e2, abs=2e-6)
    assert e1 == pytest.approx(restitution_ode(alpha_n), abs=2e-6)


def test_restitution_closed_form_first_order():
    """Closed form to first order: the energy lost is 2 pi alpha_n/sqrt(5) of the kinetic
    energy (integral of gamma ddelta^2 over the elastic collision = Beta(1/2, 3/2)), so
    (1 - e)/alpha_n -> pi/sqrt(5) as alpha_n -> 0 (Richardson extrapolation of two runs)."""
    a1, a2 = 6.313e-3, 2 * 6.313e-3
    s1 = (1 - restitution(a1, 0.2)) / a1
    s2 = (1 - restitution(a2, 0.2)) / a2
    s0 = 2 * s1 - s2  # removes the O(alpha) term of (1 - e)/alpha
    assert s0 == pytest.approx(math.pi / math.sqrt(5.0), rel=2e-3)


def test_local_map_modulus_eq8():
    """|lambda| = 1/2 mu k_s |N| dt c cosh^-2(k_s v_t) (paper eq. 8)."""
    lam = C.local_map_modulus(C.friction_slope(50.0, 0.0, 0.099, 1000.0), 4e-9, 1e5)
    assert lam == pytest.approx(0.5 * 0.099 * 1000 * 50 * 4e-9 * 1e5)
    assert C.local_map_modulus(C.friction_slope(50.0, 1e-2, 0.099, 1000.0), 4e-9, 1e5) < lam


@pytest.mark.parametrize("v0, decay", [(2e-4, 0.3), (2e-3, 5.0), (-0.05, 40.0), (0.5, 1e3), (36.0, 2e4), (-36.0, 4e4)])
def test_slip_after_friction_solves_the_friction_ode(v0, decay):
    """slip_after_friction equals a tight numerical solution of dv/dt = -m_t^-1 mu N tanh(k_s v)
    (eq. 5), never changes sign and only decays, also where sinh(k_s v) overflows."""
    from scipy.integrate import solve_ivp

    mu, k_s, n, inv_m = 0.1, 1000.0, 50.0, 100.0
    dt = decay / (mu * k_s * n * inv_m)  # decay = stick relaxation rate x dt
    got = C.slip_after_friction(v0, n, mu, k_s, inv_m, dt)
    sol = solve_ivp(
        lambda t, v: -inv_m * mu * n * np.tanh(k_s * v), (0.0, dt), [v0], method="Radau", rtol=1e-12, atol=1e-15
    )
    assert got == pytest.approx(sol.y[0, -1], rel=1e-7, abs=1e-12)
    assert 0.0 <= got / v0 <= 1.0
    if abs(k_s * v0) > 30.0 and inv_m * mu * n * dt < abs(v0) / 2:  # gross slip: Coulomb deceleration
        assert got == pytest.approx(v0 - math.copysign(inv_m * mu * n * dt, v0), rel=1e-12)

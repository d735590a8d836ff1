"""Reference solutions for elastic plates and sphere impacts (granplate.verification:
plate_theory, plate_ritz, impact_theory) against their published numbers, closed forms,
limits and energy balances."""

from __future__ import annotations

import math

import numpy as np
import pytest

from granplate.verification import impact_theory as I
from granplate.verification import plate_ritz as R
from granplate.verification import plate_theory as T

STEEL = {"young": 210e9, "poisson": 0.3, "rho": 7800.0}


# --------------------------------------------------------------------------- Kirchhoff frequencies


def test_ritz_simply_supported_equals_navier():
    """Ritz on a simply supported square and on a 1 x 1.5 rectangle gives Navier's
    pi^2 (m^2 + n^2 (a/b)^2) (Leissa 1969, ch. 4)."""
    for aspect in (1.0, 1.5):
        ritz = R.kirchhoff_frequency_parameters("S", count=6, aspect=aspect, n_terms=12)
        np.testing.assert_allclose(ritz, T.ss_frequency_parameters(6, aspect), rtol=1e-6)


def test_ss_square_closed_form_values():
    """Navier's square: lambda^2 = 2 pi^2, 5 pi^2 (twice), 8 pi^2, 10 pi^2 (twice)."""
    np.testing.assert_allclose(T.ss_frequency_parameters(6), math.pi**2 * np.array([2, 5, 5, 8, 10, 10]))


def test_clamped_square_matches_leissa():
    """Leissa 1969 (NASA SP-160, ch. 4), CCCC square, the six lowest lambda^2 = 35.99,
    73.41, 73.41, 108.27, 131.64, 132.24: Ritz (Legendre polynomials, converged) within
    0.05 % and below them (Leissa's are beam-function Ritz upper bounds)."""
    ritz = R.kirchhoff_frequency_parameters("C", count=6, n_terms=12)
    leissa = np.array(T.LEISSA_CCCC_SQUARE)
    np.testing.assert_allclose(ritz, leissa, rtol=5e-4)
    assert np.all(ritz <= leissa * (1 + 1e-5))


def test_ritz_converges_from_above():
    """Ritz frequencies are upper bounds that fall as terms are added (Rayleigh's principle),
    here for the clamped and the free square, and settle to 1e-5."""
    for edges in ("C", "F"):
        coarse, mid, fine = (R.kirchhoff_frequency_parameters(edges, count=6, n_terms=n) for n in (6, 10, 14))
        assert np.all(coarse >= mid - 1e-9) and np.all(mid >= fine - 1e-9)
        np.testing.assert_allclose(mid, fine, rtol=1e-5)


def test_free_square_has_three_rigid_modes():
    """A free plate has exactly three rigid-body modes (w = 1, x, y), all of zero frequency."""
    from scipy.linalg import eigh

    values = eigh(*R.kirchhoff_matrices("F", 1.0, 0.3, 8), eigvals_only=True)
    assert np.sum(np.abs(values) < 1e-8 * values.max()) == 3


def test_kirchhoff_frequency_units():
    """omega = lambda^2 / a^2 sqrt(D / (rho h)) with D = E h^3 / (12 (1 - nu^2)), by hand for
    a 1 m steel square 10 mm thick, mode (1, 1)."""
    d = T.flexural_rigidity(STEEL["young"], 0.01, STEEL["poisson"])
    assert d == pytest.approx(210e9 * 1e-6 / (12 * 0.91))
    omega = T.kirchhoff_frequency(2 * math.pi**2, 1.0, d, STEEL["rho"], 0.01)
    assert omega == pytest.approx(2 * math.pi**2 * math.sqrt(d / 78.0))


# --------------------------------------------------------------------------- Mindlin


def test_mindlin_ss_tends_to_kirchhoff():
    """Mindlin's simply supported root tends to Kirchhoff's pi^2 (m^2 + n^2) as h/a -> 0,
    the gap shrinking as (h/a)^2."""
    for m, n in ((1, 1), (2, 1), (3, 2)):
        exact = T.ss_frequency_parameter(m, n)
        gaps = [1 - T.mindlin_ss_frequency_parameter(m, n, t) / exact for t in (1e-4, 1e-3, 2e-3)]
        assert 0 < gaps[0] < 1e-6
        assert gaps[2] / gaps[1] == pytest.approx(4.0, rel=1e-2)


def test_mindlin_ss_eigenproblem_equals_closed_roots():
    """The 3 x 3 eigenproblem of Navier's mode and Mindlin's closed roots (the flexural and
    thickness-shear quadratic, the thickness-twist root) agree, for square and rectangular
    plates, thin to thick."""
    for m, n, t, aspect in ((1, 1, 0.01, 1.0), (2, 3, 0.1, 1.0), (1, 2, 0.2, 1.5), (3, 1, 0.05, 0.7)):
        k, mass = T.mindlin_ss_matrices(m, n, t, aspect)
        scale = 1 / np.sqrt(np.diag(mass))
        eigen = np.sqrt(np.linalg.eigvalsh(k * np.outer(scale, scale)))
        np.testing.assert_allclose(eigen, sorted(T.mindlin_ss_roots(m, n, t, aspect)), rtol=1e-9)


def test_mindlin_ss_tends_to_rayleigh_plate():
    """With S = kappa G h / D -> infinity (kappa -> infinity) Mindlin's flexural root is the
    plate with rotary inertia alone, omega^2 = k^4 / (1 + (h/a)^2 k^2 / 12)."""
    k2, t = 5 * math.pi**2, 0.1
    rigid_shear = T.mindlin_ss_frequency_parameter(1, 2, t, kappa=1e9)
    assert rigid_shear == pytest.approx(math.sqrt(k2**2 / (1 + t**2 * k2 / 12)), rel=1e-9)


def test_mindlin_ss_closed_form_equals_ritz():
    """The closed form (Navier's modes in Mindlin's equations) and the independent Ritz
    solution of Mindlin's energy agree for the simply supported square, h/a = 0.05 to 0.2."""
    for t in (0.05, 0.1, 0.2):
        ritz = R.mindlin_frequency_parameters("S", t, count=4, n_terms=10)
        np.testing.assert_allclose(ritz, T.mindlin_ss_frequency_parameters(4, t), rtol=2e-5)


def test_mindlin_ss_lower_than_kirchhoff():
    """Shear and rotary inertia soften a plate: Mindlin's frequency falls below Kirchhoff's
    and falls further with thickness."""
    values = [T.mindlin_ss_frequency_parameter(1, 1, t) for t in (0.01, 0.05, 0.1, 0.15, 0.2)]
    assert values[0] < 2 * math.pi**2 and np.all(np.diff(values) < 0)


def test_mindlin_clamped_tends_to_kirchhoff_clamped():
    """The clamped Mindlin square's Ritz frequencies approach the Kirchhoff clamped square's
    (and Leissa's) as h/a -> 0: within 0.15 % at h/a = 0.01, the gap shrinking as (h/a)^2."""
    kirchhoff = R.kirchhoff_frequency_parameters("C", count=1, n_terms=12)[0]
    gaps = [1 - R.mindlin_frequency_parameters("C", t, count=1, n_terms=12)[0] / kirchhoff for t in (0.01, 0.02)]
    assert 0 < gaps[0] < 1.5e-3
    assert gaps[1] / gaps[0] == pytest.approx(4.0, rel=0.05)


def test_shear_frequency_parameter():
    """omega h sqrt(rho / G) = lambda^2 (h/a)^2 / sqrt(6 (1 - nu)), from G, D and rho h in SI."""
    e, nu, rho, h, a = 70e9, 0.3, 2700.0, 0.02, 0.4
    d = T.flexural_rigidity(e, h, nu)
    omega = T.kirchhoff_frequency(30.0, a, d, rho, h)
    g = e / (2 * (1 + nu))
    assert T.shear_frequency_parameter(30.0, h / a, nu) == pytest.approx(omega * h * math.sqrt(rho / g))


# --------------------------------------------------------------------------- statics


def test_navier_uniform_matches_timoshenko():
    """Timoshenko & Woinowsky-Krieger ch. 5, simply supported square, uniform load:
    w_max = 0.00406 q a^4 / D (the patch series with the patch the whole plate)."""
    w = T.navier_patch_deflection(0.5, 0.5, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, terms=60)
    assert w == pytest.approx(T.TIMOSHENKO_CENTRE_DEFLECTION["S", "uniform"], abs=5e-6)


def test_navier_point_matches_timoshenko():
    """Timoshenko & Woinowsky-Krieger ch. 5, simply supported square, central point load:
    w_max = 0.01160 P a^2 / D; the series converged (400 and 800 terms agree to 1e-5)."""
    w = T.navier_point_deflection(0.5, 0.5, 1.0, 1.0, 1.0, 1.0, terms=400)
    assert w == pytest.approx(T.TIMOSHENKO_CENTRE_DEFLECTION["S", "point"], abs=5e-6)
    assert T.navier_point_deflection(0.5, 0.5, 1.0, 1.0, 1.0, 1.0, terms=800) == pytest.approx(w, rel=1e-5)


def test_small_patch_tends_to_point_load():
    """The patch of area u v carrying q0 u v = P tends to the point load as u, v -> 0, the
    gap falling with the patch (a 2 x 1 rectangle, load off centre, sampled elsewhere)."""
    a, b, x0, y0 = 2.0, 1.0, 0.7, 0.4
    point = T.navier_point_deflection(1.2, 0.5, a, b, 1.0, 1.0, x0, y0, terms=300)
    gaps = [
        abs(T.navier_patch_deflection(1.2, 0.5, a, b, 1.0, 1.0 / s**2, s, s, x0, y0, terms=300) - point)
        for s in (0.2, 0.1, 0.05)
    ]
    assert gaps[0] > gaps[1] > gaps[2] and gaps[2] < 1e-3 * point


def test_ritz_statics_equal_navier():
    """Ritz's centre deflection of the simply supported square equals Navier's series:
    uniform load to 1e-6, point load (Richardson from 16 and 32 terms) to 1e-4."""
    navier_q = T.navier_patch_deflection(0.5, 0.5, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, terms=200)
    navier_p = T.navier_point_deflection(0.5, 0.5, 1.0, 1.0, 1.0, 1.0, terms=800)
    assert R.kirchhoff_centre_deflection("S", "uniform", n_terms=12) == pytest.approx(navier_q, rel=1e-6)
    assert R.point_load_deflection_extrapolated("S", n_terms=32) == pytest.approx(navier_p, rel=1e-4)


def test_clamped_statics_match_timoshenko():
    """Timoshenko & Woinowsky-Krieger ch. 6, clamped square: w_max = 0.00126 q a^4 / D
    (uniform) and 0.00560 P a^2 / D (central load), within 0.5 %: Ritz converges to
    0.0012653 and 0.005610, 0.4 % and 0.2 % above Timoshenko's three-digit coefficients."""
    uniform = R.kirchhoff_centre_deflection("C", "uniform", n_terms=12)
    assert uniform == pytest.approx(T.TIMOSHENKO_CENTRE_DEFLECTION["C", "uniform"], rel=5e-3)
    point = R.point_load_deflection_extrapolated("C", n_terms=32)
    assert point == pytest.approx(T.TIMOSHENKO_CENTRE_DEFLECTION["C", "point"], rel=5e-3)


def test_ritz_point_load_converges_from_below():
    """Ritz's point-load compliance is a lower bound that rises with the terms."""
    values = [R.kirchhoff_centre_deflection("C", "point", n_terms=n) for n in (8, 16, 24)]
    assert values[0] < values[1] < values[2] < R.point_load_deflection_extrapolated("C", n_terms=32)


# --------------------------------------------------------------------------- Hertz


def test_hertz_time_constant_is_johnsons():
    """Johnson 1985 section 11.4: t_c = 2.94 delta_max / v0; the exact constant (4/5) B(2/5, 1/2)
    rounds to it, and equals 2 int_0^1 dx / sqrt(1 - x^(5/2)) by quadrature."""
    from scipy.integrate import quad

    assert round(I.HERTZ_TIME_CONSTANT, 2) == 2.94
    integral, _ = quad(lambda x: 1 / math.sqrt(1 - x**2.5), 0, 1, limit=200)
    assert I.HERTZ_TIME_CONSTANT == pytest.approx(2 * integral, rel=1e-8)


@pytest.mark.parametrize("speed", [0.1, 1.0, 5.0])
def test_hertz_impact_integration_equals_closed_form(speed):
    """The scipy integration of m x'' = -(4/3) E* sqrt(R) x^(3/2) gives Johnson's contact
    time, largest overlap and peak force, and an elastic rebound (steel sphere on a rigid
    flat, R = 5 mm)."""
    r = 0.005
    m = 4 / 3 * math.pi * r**3 * STEEL["rho"]
    e_star = I.effective_modulus(STEEL["young"], STEEL["poisson"])
    hit = I.hertz_impact(m, speed, e_star, r)
    assert hit.contact_time == pytest.approx(I.hertz_contact_time(m, speed, e_star, r), rel=1e-8)
    assert hit.max_overlap == pytest.approx(I.hertz_max_overlap(m, speed, e_star, r), rel=1e-6)
    assert hit.peak_force == pytest.approx(I.hertz_peak_force(m, speed, e_star, r), rel=1e-6)
    assert hit.rebound_speed == pytest.approx(speed, rel=1e-8)


def test_effective_modulus():
    """1 / E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2: two equal steels halve the rigid-flat E*."""
    rigid = I.effective_modulus(210e9, 0.3)
    assert rigid == pytest.approx(210e9 / 0.91)
    assert I.effective_modulus(210e9, 0.3, 210e9, 0.3) == pytest.approx(rigid / 2)


# --------------------------------------------------------------------------- Zener


def test_zener_energy_balance():
    """Kinetic + Hertz + dashpot energy = the initial 1/2 m v0^2 at every step, lambda = 0 to 5."""
    for lam in (0.0, 0.1, 0.5, 2.0, 5.0):
        impact = I.zener_impact(lam)
        np.testing.assert_allclose(I.zener_energy(impact), 0.5, atol=1e-9)
        assert impact.restitution**2 == pytest.approx(1 - 2 * impact.dissipated[-1], abs=1e-9)


def test_zener_rigid_limit_is_hertz():
    """lambda = 0 is Hertz's elastic impact (Johnson 1985, section 11.4) in these units
    (overlap (m v0^2/k)^(2/5)): e = 1, delta_max = (5/4)^(2/5), contact time 2.9432 delta_max,
    peak force delta_max^(3/2) = (5/4)^(3/5)."""
    impact = I.zener_impact(0.0)
    assert impact.restitution == pytest.approx(1.0, abs=1e-9)
    assert impact.contact_time == pytest.approx(I.HERTZ_TIME_CONSTANT * 1.25**0.4, rel=1e-9)
    assert impact.peak_force == pytest.approx(1.25**0.6, rel=1e-9)


def test_zener_first_order_loss():
    """For small lambda, 1 - e^2 = c lambda with c = (8/5)(5/4)^(8/5) B(8/5, 1/2) = 3.460, the
    dashpot's work on the rigid Hertz impact (Richardson from lambda = 1e-3, 2e-3)."""
    ratio = [(1 - I.zener_restitution(lam) ** 2) / lam for lam in (1e-3, 2e-3)]
    assert 2 * ratio[0] - ratio[1] == pytest.approx(I.zener_first_order_loss(), rel=1e-4)
    assert I.zener_first_order_loss() == pytest.approx(3.4603, abs=1e-4)


def test_zener_restitution_falls_with_lambda():
    """e(lambda) falls monotonically from 1 toward 0 as the plate grows more compliant."""
    values = [I.zener_restitution(lam) for lam in (0.0, 0.1, 0.3, 0.6, 1.0, 2.0, 4.0)]
    assert values[0] == pytest.approx(1.0) and np.all(np.diff(values) < 0) and 0 < values[-1] < 0.01


def test_zener_depends_on_lambda_alone():
    """The SI model m y'' = -F, F = k (y - w)^(3/2), w' = F / (8 sqrt(D rho h)) gives the
    restitution of the non-dimensional one at Zener's lambda, for two steel spheres on two
    plates with very different masses, speeds and thicknesses; and the sphere form of
    lambda equals the general one."""
    for r, speed, h in ((0.005, 1.0, 0.002), (0.02, 0.05, 0.01)):
        m = 4 / 3 * math.pi * r**3 * STEEL["rho"]
        e_star = I.effective_modulus(STEEL["young"], STEEL["poisson"], STEEL["young"], STEEL["poisson"])
        k = I.hertz_stiffness(e_star, r)
        mobility = I.plate_point_mobility(T.flexural_rigidity(STEEL["young"], h, STEEL["poisson"]), STEEL["rho"], h)
        lam = I.zener_inelasticity(m, speed, k, mobility)
        assert lam == pytest.approx(
            I.zener_inelasticity_sphere(
                r, STEEL["rho"], e_star, speed, h, STEEL["young"], STEEL["poisson"], STEEL["rho"]
            ),
            rel=1e-12,
        )
        assert I.zener_impact_si(m, speed, k, mobility) == pytest.approx(I.zener_restitution(lam), abs=1e-8)


def test_bad_arguments_are_refused_by_name():
    """A negative inelasticity, an unknown edge kind or load, a thickness ratio <= 0 and a
    free plate under load are refused, the argument named."""
    with pytest.raises(ValueError, match="inelasticity"):
        I.zener_impact(-0.1)
    with pytest.raises(ValueError, match="edges"):
        R.kirchhoff_frequency_parameters("X")
    with pytest.raises(ValueError, match="load"):
        R.kirchhoff_centre_deflection("C", "line")
    with pytest.raises(ValueError, match="free"):
        R.kirchhoff_centre_deflection("F", "uniform")
    for bad in (0.0, -0.1):
        with pytest.raises(ValueError, match="h_over_a"):
            T.mindlin_ss_frequency_parameter(1, 1, bad)
        with pytest.raises(ValueError, match="h_over_a"):
            R.mindlin_frequency_parameters("C", bad)


# --------------------------------------------------------------------------- flexural waves


def test_flexural_group_velocity_is_d_omega_dk():
    """c_g = d omega / dk of omega = k^2 sqrt(D / (rho h)), by central differences in k, and
    c = omega / k: the group velocity twice the phase velocity."""
    d, rho, h, omega = T.flexural_rigidity(70e9, 0.003, 0.33), 2700.0, 0.003, 2 * math.pi * 5e3
    root = math.sqrt(d / (rho * h))
    k = math.sqrt(omega / root)
    dk = 1e-6 * k
    numeric = ((k + dk) ** 2 - (k - dk) ** 2) * root / (2 * dk)
    assert I.flexural_group_velocity(omega, d, rho, h) == pytest.approx(numeric, rel=1e-9)
    assert I.flexural_phase_velocity(omega, d, rho, h) == pytest.approx(omega / k, rel=1e-12)


def test_reflection_time():
    """t_r = 2 L / c_g: a wave of the Hertz pulse's frequency pi / t_c, an edge 0.1 m away."""
    d, rho, h = T.flexural_rigidity(210e9, 0.002, 0.3), 7800.0, 0.002
    omega = I.hertz_pulse_frequency(2e-5)
    assert omega == pytest.approx(math.pi / 2e-5)
    t_r = I.reflection_time(0.1, omega, d, rho, h)
    assert t_r * I.flexural_group_velocity(omega, d, rho, h) == pytest.approx(0.2)

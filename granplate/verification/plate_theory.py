"""Reference solutions for elastic plates (docs/model.md section 4.6).

Closed forms and published tables, each from its source, in SI units or as the
non-dimensional parameters their sources tabulate:

- Kirchhoff plate frequencies: omega = lambda^2 / a^2 sqrt(D / (rho h)),
  D = E h^3 / (12 (1 - nu^2)); simply supported rectangle in closed form
  (`ss_frequency_parameter`), the clamped square from Leissa's table
  (`LEISSA_CCCC_SQUARE`);
- the simply supported Mindlin plate: Navier's modes turn Mindlin's equations into a
  3 x 3 eigenproblem per (m, n) whose lowest root is the flexural frequency
  (`mindlin_ss_frequency_parameter`);
- static deflections: Navier's double series for a simply supported rectangle under a
  uniform load on a rectangular patch or a point load (Timoshenko & Woinowsky-Krieger,
  Theory of Plates and Shells, 2nd ed., 1959, ch. 5), and Timoshenko's tabulated
  centre-deflection coefficients (`TIMOSHENKO_CENTRE_DEFLECTION`).

The plates no closed form covers (clamped, free, clamped Mindlin) are computed by the
independent Ritz solver `plate_ritz`; the tests hold each against the other.
"""

from __future__ import annotations

import math

import numpy as np

#: Leissa, Vibration of Plates, NASA SP-160 (1969), ch. 4, the plate clamped on all sides
#: (CCCC), the square: the six lowest lambda^2 = omega a^2 sqrt(rho h / D), as tabulated
#: (independent of nu for clamped edges; each lies just above the converged Ritz value of
#: `plate_ritz`, as a Ritz upper bound does).
LEISSA_CCCC_SQUARE = (35.99, 73.41, 73.41, 108.27, 131.64, 132.24)

#: Timoshenko & Woinowsky-Krieger (1959), the centre deflection of a square plate as
#: w = alpha q a^4 / D (uniform load q) or w = alpha P a^2 / D (central point load P),
#: nu = 0.3: simply supported, ch. 5 (Navier's solution, the tables for b / a = 1);
#: clamped, ch. 6 (the plate with built-in edges, b / a = 1). Three significant digits.
TIMOSHENKO_CENTRE_DEFLECTION = {
    ("S", "uniform"): 0.00406,
    ("S", "point"): 0.01160,
    ("C", "uniform"): 0.00126,
    ("C", "point"): 0.00560,
}


# --------------------------------------------------------------------------- Kirchhoff


def flexural_rigidity(young: float, thickness: float, poisson: float) -> float:
    """D = E h^3 / (12 (1 - nu^2)) [N m]."""
    return young * thickness**3 / (12.0 * (1.0 - poisson**2))


def kirchhoff_frequency(parameter: float, side: float, rigidity: float, rho: float, thickness: float) -> float:
    """omega = lambda^2 / a^2 sqrt(D / (rho h)) [rad/s] of the frequency parameter
    lambda^2 (Leissa 1969, ch. 4) on a plate of side a [m]."""
    return parameter / side**2 * math.sqrt(rigidity / (rho * thickness))


def ss_frequency_parameter(m: int, n: int, aspect: float = 1.0) -> float:
    """lambda^2 = pi^2 (m^2 + n^2 (a / b)^2) of mode (m, n) of a simply supported
    rectangle a x b, b = aspect a (Navier; Leissa 1969, ch. 4)."""
    return math.pi**2 * (m**2 + (n / aspect) ** 2)


def ss_frequency_parameters(count: int, aspect: float = 1.0) -> np.ndarray:
    """The `count` lowest lambda^2 of a simply supported rectangle, repeated roots kept."""
    top = count + 2
    values = sorted(ss_frequency_parameter(m, n, aspect) for m in range(1, top) for n in range(1, top))
    return np.array(values[:count])


# --------------------------------------------------------------------------- Mindlin, simply supported


def mindlin_ss_matrices(
    m: int, n: int, h_over_a: float, aspect: float = 1.0, nu: float = 0.3, kappa: float = 5.0 / 6.0
) -> tuple[np.ndarray, np.ndarray]:
    """(K, M), 3 x 3, of Navier's mode (m, n) of a simply supported Mindlin plate in units
    a = D = rho h = 1: w = W sin(alpha x) sin(beta y), psi_x = X cos(alpha x) sin(beta y),
    psi_y = Y sin(alpha x) cos(beta y), alpha = m pi / a, beta = n pi / b, put into Mindlin's
    energy (J. Appl. Mech. 18, 31, 1951), S = kappa G h / D = 6 kappa (1 - nu) / (h/a)^2:
    K = [[S (alpha^2 + beta^2), S alpha, S beta],
         [S alpha, alpha^2 + (1 - nu)/2 beta^2 + S, (1 + nu)/2 alpha beta],
         [S beta, (1 + nu)/2 alpha beta, beta^2 + (1 - nu)/2 alpha^2 + S]],
    M = diag(1, h^2/12, h^2/12). det(K - omega^2 M) = 0 is Mindlin's cubic in omega^2."""
    if not h_over_a > 0.0:
        raise ValueError(f"h_over_a must be > 0, not {h_over_a!r}")
    alpha, beta = m * math.pi, n * math.pi / aspect
    s = 6.0 * kappa * (1.0 - nu) / h_over_a**2
    k = np.array(
        [
            [s * (alpha**2 + beta**2), s * alpha, s * beta],
            [s * alpha, alpha**2 + (1 - nu) / 2 * beta**2 + s, (1 + nu) / 2 * alpha * beta],
            [s * beta, (1 + nu) / 2 * alpha * beta, beta**2 + (1 - nu) / 2 * alpha**2 + s],
        ]
    )
    rot = h_over_a**2 / 12.0
    return k, np.diag([1.0, rot, rot])


def mindlin_ss_frequency_parameter(
    m: int, n: int, h_over_a: float, aspect: float = 1.0, nu: float = 0.3, kappa: float = 5.0 / 6.0
) -> float:
    """lambda^2 = omega a^2 sqrt(rho h / D) of the flexural (lowest) root of Mindlin's
    cubic for mode (m, n) of a simply supported rectangle (hard supports: w = 0, the
    rotation along the edge = 0); tends to pi^2 (m^2 + n^2 (a/b)^2) as h / a -> 0. From
    the closed roots (`mindlin_ss_roots`), exact to rounding however thin the plate; the
    eigenproblem of `mindlin_ss_matrices` is the check on them."""
    return mindlin_ss_roots(m, n, h_over_a, aspect, nu, kappa)[0]


def mindlin_ss_roots(
    m: int, n: int, h_over_a: float, aspect: float = 1.0, nu: float = 0.3, kappa: float = 5.0 / 6.0
) -> tuple[float, float, float]:
    """The three lambda^2 of mode (m, n) in closed form (units a = D = rho h = 1,
    k^2 = alpha^2 + beta^2, S = 6 kappa (1 - nu) / (h/a)^2, r = (h/a)^2 / 12): the rotations
    split into a gradient and a curl. The curl (thickness-twist) root is
    omega^2 = ((1 - nu)/2 k^2 + S) / r; the gradient and w give Mindlin's quadratic
    r omega^4 - (r S k^2 + k^2 + S) omega^2 + S k^4 = 0, whose smaller root is the
    flexural mode and the larger the thickness-shear mode (Mindlin, Schacknow &
    Deresiewicz, J. Appl. Mech. 23, 430, 1956, the simply supported plate).
    Returns (flexural, thickness-shear, thickness-twist) as lambda^2 = omega."""
    if not h_over_a > 0.0:
        raise ValueError(f"h_over_a must be > 0, not {h_over_a!r}")
    k2 = (m * math.pi) ** 2 + (n * math.pi / aspect) ** 2
    s = 6.0 * kappa * (1.0 - nu) / h_over_a**2
    r = h_over_a**2 / 12.0
    b, c = r * s * k2 + k2 + s, s * k2 * k2
    root = math.sqrt(b * b - 4.0 * r * c)
    flexural = 2.0 * c / (b + root)  # the smaller root, without cancellation
    shear = (b + root) / (2.0 * r)
    twist = ((1.0 - nu) / 2.0 * k2 + s) / r
    return math.sqrt(flexural), math.sqrt(shear), math.sqrt(twist)


def mindlin_ss_frequency_parameters(
    count: int, h_over_a: float, aspect: float = 1.0, nu: float = 0.3, kappa: float = 5.0 / 6.0
) -> np.ndarray:
    """The `count` lowest flexural lambda^2 of a simply supported Mindlin rectangle."""
    top = count + 2
    values = sorted(
        mindlin_ss_frequency_parameter(m, n, h_over_a, aspect, nu, kappa) for m in range(1, top) for n in range(1, top)
    )
    return np.array(values[:count])


def shear_frequency_parameter(parameter: float, h_over_a: float, nu: float = 0.3) -> float:
    """omega h sqrt(rho / G) from lambda^2 = omega a^2 sqrt(rho h / D): the two differ by
    (h/a)^2 / sqrt(6 (1 - nu)) (G = E / (2 (1 + nu)), D = E h^3 / (12 (1 - nu^2)))."""
    return parameter * h_over_a**2 / math.sqrt(6.0 * (1.0 - nu))


# --------------------------------------------------------------------------- statics (Navier)


def _indices(terms: int) -> np.ndarray:
    """1, 2, ..., terms as floats (the even terms vanish at a centred load by sin(k pi / 2))."""
    return np.arange(1, terms + 1, dtype=float)


def navier_patch_deflection(
    x: float,
    y: float,
    a: float,
    b: float,
    rigidity: float,
    q0: float,
    u: float,
    v: float,
    x0: float | None = None,
    y0: float | None = None,
    terms: int = 200,
) -> float:
    """w(x, y) [m] of a simply supported rectangle a x b under a uniform pressure q0 [Pa]
    on a patch u x v centred at (x0, y0) (default: the plate's centre), Navier's series
    (Timoshenko & Woinowsky-Krieger 1959, ch. 5, eqs. for a load over a rectangle):
    w = sum_{m,n} q_mn sin(m pi x / a) sin(n pi y / b) / (pi^4 D (m^2/a^2 + n^2/b^2)^2),
    q_mn = 16 q0 / (pi^2 m n) sin(m pi x0 / a) sin(n pi y0 / b) sin(m pi u / 2a) sin(n pi v / 2b).
    `terms` terms in each direction."""
    x0 = a / 2 if x0 is None else x0
    y0 = b / 2 if y0 is None else y0
    m = _indices(terms)[:, None]
    n = _indices(terms)[None, :]
    q = (
        16.0
        * q0
        / (math.pi**2 * m * n)
        * np.sin(m * math.pi * x0 / a)
        * np.sin(n * math.pi * y0 / b)
        * np.sin(m * math.pi * u / (2 * a))
        * np.sin(n * math.pi * v / (2 * b))
    )
    shape = np.sin(m * math.pi * x / a) * np.sin(n * math.pi * y / b)
    return float(np.sum(q * shape / (math.pi**4 * rigidity * (m**2 / a**2 + n**2 / b**2) ** 2)))


def navier_point_deflection(
    x: float,
    y: float,
    a: float,
    b: float,
    rigidity: float,
    force: float,
    x0: float | None = None,
    y0: float | None = None,
    terms: int = 400,
) -> float:
    """w(x, y) [m] of a simply supported rectangle under a point force P [N] at (x0, y0):
    Navier's series with q_mn = 4 P / (a b) sin(m pi x0 / a) sin(n pi y0 / b)
    (Timoshenko & Woinowsky-Krieger 1959, ch. 5); the patch series as u, v -> 0."""
    x0 = a / 2 if x0 is None else x0
    y0 = b / 2 if y0 is None else y0
    m = _indices(terms)[:, None]
    n = _indices(terms)[None, :]
    q = 4.0 * force / (a * b) * np.sin(m * math.pi * x0 / a) * np.sin(n * math.pi * y0 / b)
    shape = np.sin(m * math.pi * x / a) * np.sin(n * math.pi * y / b)
    return float(np.sum(q * shape / (math.pi**4 * rigidity * (m**2 / a**2 + n**2 / b**2) ** 2)))

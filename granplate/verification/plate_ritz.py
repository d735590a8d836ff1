"""An independent Rayleigh-Ritz solver for rectangular plates (references, docs/model.md
section 4.6).

Kirchhoff and Mindlin plates with the same condition on all four edges, clamped ("C"),
simply supported ("S") or free ("F"), solved from their energy functionals with tensor
products of Legendre polynomials times the factor (1 - xi^2)^p that imposes the
essential conditions (p = 2 clamped, 1 simply supported, 0 free for a Kirchhoff
deflection; p = 1 on an edge where a Mindlin field must vanish). Ritz's method gives
upper bounds of the frequencies that fall as terms are added (Leissa, Vibration of
Plates, NASA SP-160, 1969, ch. 1), and the static deflection under a load converges
from below. Everything is non-dimensional: side a = 1, D = 1, rho h = 1, so a frequency
comes back as the parameter lambda^2 = omega a^2 sqrt(rho h / D) and a deflection as
w D / (q a^4) (uniform load q) or w D / (P a^2) (point load P).

Nothing here uses granplate's finite elements: it is the truth the plate tables of
`plate_theory` are checked with, and that a 3D body's verification can use where no
closed form exists (the clamped and free plates).
"""

from __future__ import annotations

import numpy as np
from numpy.polynomial import Legendre, Polynomial
from scipy.linalg import eigh, solve

#: the power p of (1 - xi^2)^p that a Kirchhoff deflection carries for each edge kind.
KIRCHHOFF_POWER = {"C": 2, "S": 1, "F": 0}


def edge_basis(n_terms: int, power: int) -> list[Polynomial]:
    """(1 - xi^2)^power P_k(xi), k < n_terms, on [-1, 1] (P_k: Legendre polynomials)."""
    weight = Polynomial([1.0, 0.0, -1.0]) ** power
    return [weight * Legendre.basis(k).convert(kind=Polynomial) for k in range(n_terms)]


def _gauss(basis_a: list[Polynomial], basis_b: list[Polynomial]) -> tuple[np.ndarray, np.ndarray]:
    degree = max(p.degree() for p in basis_a) + max(p.degree() for p in basis_b)
    return np.polynomial.legendre.leggauss(degree // 2 + 2)


def gram(basis_a: list[Polynomial], basis_b: list[Polynomial], da: int, db: int) -> np.ndarray:
    """G[i, j] = int_{-1}^{1} A_i^(da) B_j^(db) d xi, exact (Gauss-Legendre)."""
    x, wq = _gauss(basis_a, basis_b)
    va = np.array([p.deriv(da)(x) if da else p(x) for p in basis_a])
    vb = np.array([p.deriv(db)(x) if db else p(x) for p in basis_b])
    return (va * wq) @ vb.T


def _check_edges(edges: str) -> None:
    if edges not in KIRCHHOFF_POWER:
        raise ValueError(f"edges must be one of 'C', 'S', 'F', not {edges!r}")


def kirchhoff_matrices(edges: str, aspect: float, nu: float, n_terms: int) -> tuple[np.ndarray, np.ndarray]:
    """(K, M) of a Kirchhoff plate a x b, b = aspect a, a = D = rho h = 1, on the basis
    phi_i(xi) phi_j(eta), x = a xi / 2, y = b eta / 2. K from the strain energy
    D/2 int [w_xx^2 + w_yy^2 + 2 nu w_xx w_yy + 2 (1 - nu) w_xy^2] dA, M from
    rho h / 2 int w^2 dA."""
    _check_edges(edges)
    phi = edge_basis(n_terms, KIRCHHOFF_POWER[edges])
    g = {(p, q): gram(phi, phi, p, q) for p in range(3) for q in range(3)}
    sx, sy = 2.0, 2.0 / aspect  # d/dx = sx d/dxi, d/dy = sy d/deta
    area = aspect / 4.0  # dx dy = (a b / 4) dxi deta
    k = area * (
        sx**4 * np.kron(g[2, 2], g[0, 0])
        + sy**4 * np.kron(g[0, 0], g[2, 2])
        + nu * sx**2 * sy**2 * (np.kron(g[2, 0], g[0, 2]) + np.kron(g[0, 2], g[2, 0]))
        + 2.0 * (1.0 - nu) * sx**2 * sy**2 * np.kron(g[1, 1], g[1, 1])
    )
    m = area * np.kron(g[0, 0], g[0, 0])
    return k, m


def _parameters(k: np.ndarray, m: np.ndarray, count: int) -> np.ndarray:
    """The lowest `count` elastic lambda^2 = sqrt(eigenvalue) (rigid-body modes dropped)."""
    values = eigh(k, m, eigvals_only=True)
    scale = max(values.max(), 1.0)
    elastic = values[values > 1e-9 * scale]
    return np.sqrt(elastic[:count])


def kirchhoff_frequency_parameters(
    edges: str, count: int = 6, aspect: float = 1.0, nu: float = 0.3, n_terms: int = 12
) -> np.ndarray:
    """The `count` lowest lambda^2 = omega a^2 sqrt(rho h / D) of a Kirchhoff plate with
    all edges `edges` ("C", "S", "F"), b / a = aspect (Ritz upper bounds; a free plate's
    three rigid-body modes are left out)."""
    return _parameters(*kirchhoff_matrices(edges, aspect, nu, n_terms), count)


def kirchhoff_centre_deflection(
    edges: str, load: str, aspect: float = 1.0, nu: float = 0.3, n_terms: int = 12
) -> float:
    """The centre deflection of a Kirchhoff plate under a uniform load ("uniform": as
    w D / (q a^4)) or a central point load ("point": as w D / (P a^2)); edges "C" or "S"."""
    _check_edges(edges)
    if edges == "F":
        raise ValueError("edges 'F': a free plate has no static solution under a load")
    k, _ = kirchhoff_matrices(edges, aspect, nu, n_terms)
    phi = edge_basis(n_terms, KIRCHHOFF_POWER[edges])
    at_centre = np.array([p(0.0) for p in phi])
    if load == "uniform":
        one = [Polynomial([1.0])]
        f = aspect / 4.0 * np.kron(gram(phi, one, 0, 0)[:, 0], gram(phi, one, 0, 0)[:, 0])
    elif load == "point":
        f = np.kron(at_centre, at_centre)
    else:
        raise ValueError(f"load must be 'uniform' or 'point', not {load!r}")
    return float(np.kron(at_centre, at_centre) @ solve(k, f, assume_a="pos"))


def mindlin_matrices(
    edges: str, h_over_a: float, nu: float = 0.3, kappa: float = 5.0 / 6.0, n_terms: int = 10
) -> tuple[np.ndarray, np.ndarray]:
    """(K, M) of a square Mindlin plate (a = D = rho h = 1, thickness h = h_over_a) in the
    fields (w, psi_x, psi_y) from U = 1/2 int D [psi_x,x^2 + psi_y,y^2 + 2 nu psi_x,x psi_y,y
    + (1 - nu)/2 (psi_x,y + psi_y,x)^2] + kappa G h [(w_x + psi_x)^2 + (w_y + psi_y)^2] dA and
    T = omega^2 / 2 int rho h w^2 + rho h^3 / 12 (psi_x^2 + psi_y^2) dA (Mindlin, J. Appl.
    Mech. 18, 31, 1951). Essential conditions: clamped w = psi_x = psi_y = 0; simply
    supported ("hard") w = 0 and the rotation along the edge = 0; free none.
    kappa G h / D = 6 kappa (1 - nu) / h^2."""
    _check_edges(edges)
    if not h_over_a > 0.0:
        raise ValueError(f"h_over_a must be > 0, not {h_over_a!r}")
    n = n_terms
    if edges == "C":
        powers = {"w": (1, 1), "x": (1, 1), "y": (1, 1)}
    elif edges == "S":
        powers = {"w": (1, 1), "x": (0, 1), "y": (1, 0)}
    else:
        powers = {"w": (0, 0), "x": (0, 0), "y": (0, 0)}
    basis = {f: (edge_basis(n, px), edge_basis(n, py)) for f, (px, py) in powers.items()}
    shear = 6.0 * kappa * (1.0 - nu) / h_over_a**2
    s = 2.0  # d/dx = 2 d/dxi on the unit square
    area = 0.25

    def block(f1: str, d1: tuple[int, int], f2: str, d2: tuple[int, int]) -> np.ndarray:
        """int d^(d1) f1_i d^(d2) f2_j dA over the tensor basis, derivatives (d/dx, d/dy)."""
        gx = gram(basis[f1][0], basis[f2][0], d1[0], d2[0])
        gy = gram(basis[f1][1], basis[f2][1], d1[1], d2[1])
        return area * s ** (sum(d1) + sum(d2)) * np.kron(gx, gy)

    # bending: psi_x,x = x(1,0); psi_y,y = y(0,1); twist psi_x,y + psi_y,x
    kxx = (
        block("x", (1, 0), "x", (1, 0))
        + (1 - nu) / 2 * block("x", (0, 1), "x", (0, 1))
        + shear * block("x", (0, 0), "x", (0, 0))
    )
    kyy = (
        block("y", (0, 1), "y", (0, 1))
        + (1 - nu) / 2 * block("y", (1, 0), "y", (1, 0))
        + shear * block("y", (0, 0), "y", (0, 0))
    )
    kxy = nu * block("x", (1, 0), "y", (0, 1)) + (1 - nu) / 2 * block("x", (0, 1), "y", (1, 0))
    kww = shear * (block("w", (1, 0), "w", (1, 0)) + block("w", (0, 1), "w", (0, 1)))
    kwx = shear * block("w", (1, 0), "x", (0, 0))
    kwy = shear * block("w", (0, 1), "y", (0, 0))
    k = np.block([[kww, kwx, kwy], [kwx.T, kxx, kxy], [kwy.T, kxy.T, kyy]])
    rot = h_over_a**2 / 12.0
    zero = np.zeros((n * n, n * n))
    m = np.block(
        [
            [block("w", (0, 0), "w", (0, 0)), zero, zero],
            [zero, rot * block("x", (0, 0), "x", (0, 0)), zero],
            [zero, zero, rot * block("y", (0, 0), "y", (0, 0))],
        ]
    )
    return k, m


def mindlin_frequency_parameters(
    edges: str, h_over_a: float, count: int = 6, nu: float = 0.3, kappa: float = 5.0 / 6.0, n_terms: int = 10
) -> np.ndarray:
    """The `count` lowest lambda^2 = omega a^2 sqrt(rho h / D) of a square Mindlin plate
    with all edges `edges` (Ritz upper bounds). The polynomial basis locks in shear for
    h/a below about 0.005 (12 terms): the thin limit is `kirchhoff_frequency_parameters`."""
    return _parameters(*mindlin_matrices(edges, h_over_a, nu, kappa, n_terms), count)


def point_load_deflection_extrapolated(edges: str, aspect: float = 1.0, nu: float = 0.3, n_terms: int = 32) -> float:
    """The centre deflection under a central point load as w D / (P a^2), Richardson-
    extrapolated from n_terms / 2 and n_terms terms: the point load's Ritz deflection
    converges from below as n^-2 (its curvature is singular at the load), so
    w = (4 w_n - w_{n/2}) / 3."""
    fine = kirchhoff_centre_deflection(edges, "point", aspect, nu, n_terms)
    coarse = kirchhoff_centre_deflection(edges, "point", aspect, nu, n_terms // 2)
    return (4.0 * fine - coarse) / 3.0

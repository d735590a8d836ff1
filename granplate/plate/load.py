"""The shock on the plate: consistent nodal forces of the half-sine line load on its left edge."""

from __future__ import annotations

import numpy as np
from skfem import ElementQuadS2, ElementVector, FacetBasis, LinearForm, MeshQuad, asm

#: Gauss-Legendre points per (piece of) edge facet for the consistent edge load.
EDGE_LOAD_POINTS = 8


def half_sine_line_load(y: np.ndarray, y0_load: float, length: float) -> np.ndarray:
    """q(y) / q0 = sin(pi (y - y0_load) / L) on [y0_load, y0_load + L], zero elsewhere [-]."""
    s = (y - y0_load) / length
    return np.where((s >= 0.0) & (s <= 1.0), np.sin(np.pi * np.clip(s, 0.0, 1.0)), 0.0)


def _gauss_on(a: float, b: float, n: int) -> tuple[np.ndarray, np.ndarray]:
    """n-point Gauss-Legendre rule on the reference-facet interval [a, b] within [0, 1]."""
    xi, wi = np.polynomial.legendre.leggauss(n)
    return (0.5 * (b - a) * xi + 0.5 * (a + b))[None, :], 0.5 * (b - a) * wi


def edge_load_vector(
    mesh: MeshQuad,
    x_edge: float,
    y0_load: float,
    length: float,
    tol: float,
    n_points: int = EDGE_LOAD_POINTS,
) -> np.ndarray:
    """Consistent nodal forces [N] (x direction) of the half-sine line load, q0 = 1 N/m.

    The load q(y) = sin(pi (y - y0_load) / L) acts on y0_load <= y <= y0_load + L of the
    edge x = x_edge. Each facet is integrated with an n_points Gauss rule over the part
    of it inside the loaded interval (FacetBasis with an explicit quadrature), so a
    load end inside an element is integrated as accurately as one on a node.
    """
    element = ElementVector(ElementQuadS2())
    facets = mesh.facets_satisfying(lambda x: np.abs(x[0] - x_edge) <= tol)
    ya = mesh.p[1, mesh.facets[0, facets]]
    yb = mesh.p[1, mesh.facets[1, facets]]
    lo, hi = y0_load, y0_load + length

    @LinearForm
    def push(v, w):
        return half_sine_line_load(w.x[1], y0_load, length) * v[0]

    f = np.zeros(2 * (mesh.p.shape[1] + mesh.facets.shape[1]))
    groups: dict[tuple[float, float], list[int]] = {}
    for fac, a, b in zip(facets, ya, yb):
        y_lo, y_hi = max(min(a, b), lo), min(max(a, b), hi)  # loaded part of this facet
        if y_hi <= y_lo:
            continue
        s_lo, s_hi = sorted(float(np.clip((y - a) / (b - a), 0.0, 1.0)) for y in (y_lo, y_hi))
        groups.setdefault((s_lo, s_hi), []).append(int(fac))
    for (s_lo, s_hi), facs in groups.items():
        fb = FacetBasis(mesh, element, facets=np.array(facs), quadrature=_gauss_on(s_lo, s_hi, n_points))
        f += asm(push, fb)
    # Shape functions of nodes off a facet vanish on it: clear their round-off (~1e-18).
    on_edge = np.concatenate([mesh.facets[:, facets].ravel(), mesh.p.shape[1] + facets])
    keep = np.zeros_like(f, dtype=bool)
    keep[2 * on_edge] = True
    return np.where(keep, f, 0.0)

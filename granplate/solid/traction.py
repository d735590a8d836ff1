"""The paper's line load on a 3D box solid's face xmin (docs/model.md section 5.2 in space):
the bare plate's shock q(y, t) = q0 sin(pi t / T) sin(pi (y - y0) / L) [N/m] spread
evenly over the face's extent along z, a traction t_x = q / L_z [Pa] in +x, turned into
consistent nodal forces f_a = integral of N_a t_x dA over the face's quadratic faces
(Gauss quadrature of the face: 3 x 3 points on a quadrilateral, 6 on a triangle).
"""

from __future__ import annotations

import math

import numpy as np

from granplate.solid.surface import TRI6, Surface, face_shape_functions

#: Gauss points (xi, eta) and weights of a quadrilateral face, 3 x 3 on [-1, 1]^2.
_G3 = (-math.sqrt(0.6), 0.0, math.sqrt(0.6))
_W3 = (5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0)
QUAD_POINTS = tuple((a, b, wa * wb) for a, wa in zip(_G3, _W3) for b, wb in zip(_G3, _W3))
#: A triangle face's points (xi, eta) and weights on the reference triangle (Strang and
#: Fix's 6-point rule, degree 4; the weights sum to its area 1/2).
_A, _B = 0.445948490915965, 0.091576213509771
_WA, _WB = 0.5 * 0.223381589678011, 0.5 * 0.109951743655322
TRI_POINTS = (
    (_A, _A, _WA),
    (1.0 - 2.0 * _A, _A, _WA),
    (_A, 1.0 - 2.0 * _A, _WA),
    (_B, _B, _WB),
    (1.0 - 2.0 * _B, _B, _WB),
    (_B, 1.0 - 2.0 * _B, _WB),
)


def space_profile(y: float, y0: float, length: float) -> float:
    """sin(pi (y - y0) / L) on y0 <= y <= y0 + L, else 0 [-] (docs/model.md section 5)."""
    if y < y0 or y > y0 + length:
        return 0.0
    return math.sin(math.pi * (y - y0) / length)


def face_xmin_line_load(
    surface: Surface, n_full: int, x_face: float, depth: float, y0: float, length: float, tol: float
) -> np.ndarray:
    """(n_full,) the consistent nodal forces [N] per unit q0 [N/m] of the line load on the
    faces lying in the plane x = x_face [m] (within tol [m]): the traction
    sin(pi (y - y0) / L) / depth [Pa per N/m] along +x, depth [m] the solid's extent along z."""
    points = TRI_POINTS if surface.kind == TRI6 else QUAD_POINTS
    n_fn = surface.nodes.shape[1]
    N, dN = np.empty(n_fn), np.empty((n_fn, 2))
    f = np.zeros(n_full)
    on_face = np.all(np.abs(surface.nodes[:, :, 0] - x_face) <= tol, axis=1)
    for face in np.flatnonzero(on_face):
        X = surface.nodes[face]
        for xi, eta, w in points:
            face_shape_functions(surface.kind, xi, eta, N, dN)
            J = X.T @ dN
            dA = float(np.linalg.norm(np.cross(J[:, 0], J[:, 1]))) * w
            t = space_profile(float(N @ X[:, 1]), y0, length) / depth
            if t != 0.0:
                np.add.at(f, surface.dofs[face, :, 0], N * t * dA)
    return f

"""Strain and stress recovery of the 3D solid, and the ball-averaged von Mises stress
(docs/model.md section 3.8).

Voigt order (xx, yy, zz, yz, xz, xy): strains with engineering shears gamma_ij =
du_i/dx_j + du_j/dx_i [-], stresses sigma = D eps [Pa]. Values at the quadrature points are
flat over the points: point = element * n_qp + qp, n_points = n_elem n_qp, arrays
(..., 6, n_points).

The ball average is the 3D disc average of the plate (plate/stress.py): the mean of the von
Mises stress over the ball of radius r about a centre, cut by the body, by the quadrature
points' own volume weights; the von Mises stress of the mean tensor is offered beside it
(`von_mises_of_ball_mean`, never above the first: von Mises is a norm). A point near the
sphere is weighted by a linear ramp across a band one quadrature-point spacing wide (the
partial cell), so the averaged volume converges smoothly under refinement instead of
jumping as points cross the sphere.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from skfem import Basis

from granplate.errors import ScenarioError

#: Voigt components: normal then shear, engineering shear strains.
COMPONENTS = ("xx", "yy", "zz", "yz", "xz", "xy")
_SHEAR_PAIRS = ((1, 2), (0, 2), (0, 1))


def elasticity_matrix(E: float, nu: float) -> np.ndarray:
    """The isotropic 6 x 6 D [Pa] on (eps_xx, eps_yy, eps_zz, gamma_yz, gamma_xz, gamma_xy):
    lambda + 2 mu on the normal diagonal, lambda off it, mu on the shears (lambda =
    E nu / ((1 + nu)(1 - 2 nu)), mu = E / (2 (1 + nu)))."""
    lam = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
    mu = E / (2.0 * (1.0 + nu))
    D = np.zeros((6, 6))
    D[:3, :3] = lam
    D[np.arange(3), np.arange(3)] += 2.0 * mu
    D[np.arange(3, 6), np.arange(3, 6)] = mu
    return D


def voigt_strain(grad: np.ndarray) -> np.ndarray:
    """(6, ...) strains from a displacement gradient grad[i, j] = du_i/dx_j (3, 3, ...)."""
    normal = [grad[i, i] for i in range(3)]
    shear = [grad[i, j] + grad[j, i] for i, j in _SHEAR_PAIRS]
    return np.stack(normal + shear)


def strain_operator(basis: Basis) -> sp.csr_matrix:
    """Sparse map from the dof vector to the 6 strains at the quadrature points,
    shape (6 n_points, basis.N); row = component * n_points + element * n_qp + qp."""
    n_elem, n_qp = basis.dx.shape
    n_points = n_elem * n_qp
    rows, cols, data = [], [], []
    point = np.arange(n_points).reshape(n_elem, n_qp)
    for i in range(basis.element_dofs.shape[0]):
        eps = voigt_strain(np.asarray(basis.basis[i][0].grad))  # (6, n_elem, n_qp)
        col = np.broadcast_to(basis.element_dofs[i][:, None], (n_elem, n_qp))
        for c in range(6):
            keep = eps[c] != 0.0
            if keep.any():
                rows.append(c * n_points + point[keep])
                cols.append(col[keep])
                data.append(eps[c][keep])
    op = sp.coo_matrix(
        (np.concatenate(data), (np.concatenate(rows), np.concatenate(cols))), shape=(6 * n_points, basis.N)
    ).tocsr()
    op.sum_duplicates()
    op.sort_indices()
    return op


def quadrature_points(basis: Basis) -> np.ndarray:
    """The quadrature points' coordinates [m], (n_points, 3)."""
    x = np.asarray(basis.mapping.F(basis.X))  # (3, n_elem, n_qp)
    return np.ascontiguousarray(x.reshape(3, -1).T)


def quadrature_weights(basis: Basis) -> np.ndarray:
    """The quadrature points' volume weights [m^3], (n_points,): sum = the body's volume."""
    return np.asarray(basis.dx, dtype=float).ravel()


def strains(strain_op: sp.csr_matrix, x: np.ndarray) -> np.ndarray:
    """The strains [-] (..., 6, n_points) of displacements x (..., basis.N) [m]."""
    flat = np.asarray(x, dtype=float).reshape(-1, strain_op.shape[1])
    eps = (strain_op @ flat.T).T
    return eps.reshape(np.shape(x)[:-1] + (6, strain_op.shape[0] // 6))


def stresses(D: np.ndarray, eps: np.ndarray) -> np.ndarray:
    """sigma = D eps [Pa] (..., 6, n_points) from strains (..., 6, n_points)."""
    return np.einsum("ij,...jp->...ip", D, eps)


def von_mises(sigma: np.ndarray) -> np.ndarray:
    """sqrt(((s_xx - s_yy)^2 + (s_yy - s_zz)^2 + (s_zz - s_xx)^2) / 2
    + 3 (s_yz^2 + s_xz^2 + s_xy^2)) [Pa] over the component axis -2 of (..., 6, n)."""
    s = np.asarray(sigma, dtype=float)
    sxx, syy, szz, syz, sxz, sxy = (s[..., c, :] for c in range(6))
    j2 = 0.5 * ((sxx - syy) ** 2 + (syy - szz) ** 2 + (szz - sxx) ** 2) + 3.0 * (syz**2 + sxz**2 + sxy**2)
    return np.sqrt(np.maximum(j2, 0.0))


def max_von_mises(sigma: np.ndarray) -> np.ndarray:
    """The largest von Mises stress [Pa] over the quadrature points of (..., 6, n) -> (...)."""
    return von_mises(sigma).max(axis=-1)


def modal_unit_stresses(strain_op: sp.csr_matrix, D: np.ndarray, Phi: np.ndarray) -> np.ndarray:
    """Each mode's stress at the quadrature points per unit modal coordinate,
    (n_modes, 6, n_points) [Pa per unit of q]; Phi (basis.N, n_modes) the mode shapes."""
    return stresses(D, strains(strain_op, np.asarray(Phi, dtype=float).T))


# --------------------------------------------------------------------------------------
# The ball-averaged stress
# --------------------------------------------------------------------------------------
def point_spacing(basis: Basis) -> np.ndarray:
    """The quadrature-point spacing [m] (n_points,): (element volume / n_qp)^(1/3)."""
    n_qp = basis.dx.shape[1]
    volume = np.asarray(basis.dx).sum(axis=1)
    return np.repeat(np.cbrt(volume / n_qp), n_qp)


def ball_weight(distance: np.ndarray, radius: float, spacing: np.ndarray) -> np.ndarray:
    """The share [-] of a point's cell inside the ball: 1 deep inside, 0 outside, a linear
    ramp 1/2 + (radius - distance) / spacing across the sphere; spacing 0: the indicator."""
    spacing = np.asarray(spacing, dtype=float)
    inside = (distance <= radius).astype(float)
    with np.errstate(divide="ignore", invalid="ignore"):
        ramp = np.clip(0.5 + (radius - distance) / spacing, 0.0, 1.0)
    return np.where(spacing > 0.0, ramp, inside)


def ball_average_operator(
    points: np.ndarray, weights: np.ndarray, centres: np.ndarray, radius: float, spacing: np.ndarray | float = 0.0
) -> sp.csr_matrix:
    """Sparse (n_centres, n_points) map from values at the quadrature points to their mean
    over the ball of `radius` [m] about each centre, cut by the body: row c = w_i b_i /
    sum(w b), b_i = `ball_weight` (the partial cells, `spacing` [m] per point: `point_spacing`;
    0: points inside only, as the plate's disc). A ball that holds no point gets an empty row.

    points: (n_points, 3) [m]; weights: (n_points,) [m^3]; centres: (n_centres, 3) [m]."""
    from scipy.spatial import cKDTree

    points = np.asarray(points, dtype=float)
    centres = np.atleast_2d(np.asarray(centres, dtype=float))
    spacing = np.broadcast_to(np.asarray(spacing, dtype=float), (len(points),))
    hits = cKDTree(points).query_ball_point(centres, radius + 0.5 * float(spacing.max(initial=0.0)))
    counts = np.fromiter((len(h) for h in hits), dtype=np.int64, count=len(hits))
    cols = np.concatenate([np.asarray(h, dtype=np.int64) for h in hits]) if counts.sum() else np.zeros(0, np.int64)
    rows = np.repeat(np.arange(len(hits)), counts)
    dist = np.linalg.norm(points[cols] - centres[rows], axis=1)
    w = np.asarray(weights, dtype=float)[cols] * ball_weight(dist, radius, spacing[cols])
    keep = w > 0.0
    rows, cols, w = rows[keep], cols[keep], w[keep]
    total = np.bincount(rows, weights=w, minlength=len(hits))
    op = sp.csr_matrix((w / total[rows], (rows, cols)), shape=(len(hits), len(points)))
    op.sort_indices()
    return op


def ball_mean(op: sp.csr_matrix, values: np.ndarray) -> np.ndarray:
    """The ball means (..., n_centres) of values (..., n_points) at the quadrature points."""
    v = np.asarray(values, dtype=float)
    flat = v.reshape(-1, op.shape[1])
    return (op @ flat.T).T.reshape(v.shape[:-1] + (op.shape[0],))


def ball_von_mises(op: sp.csr_matrix, sigma: np.ndarray) -> np.ndarray:
    """The mean of the von Mises stress [Pa] over each ball (..., n_centres), as the
    plate's disc mean; sigma (..., 6, n_points)."""
    return ball_mean(op, von_mises(sigma))


def von_mises_of_ball_mean(op: sp.csr_matrix, sigma: np.ndarray) -> np.ndarray:
    """The von Mises stress [Pa] of each ball's mean stress tensor (..., n_centres)."""
    return von_mises(ball_mean(op, sigma))


def max_ball_von_mises(op: sp.csr_matrix, sigma: np.ndarray) -> np.ndarray:
    """The largest ball mean of the von Mises stress over the op's centres [Pa] -> (...)."""
    return ball_von_mises(op, sigma).max(axis=-1)


def surface_centres(basis: Basis) -> np.ndarray:
    """The body's surface points [m] (n, 3): the locations of the basis' boundary nodes
    (corners, edge and face mid-points of the boundary facets), each once."""
    dofs = np.asarray(basis.get_dofs().flatten())
    return np.unique(np.round(basis.doflocs[:, dofs].T, 12), axis=0)


def ball_operator(basis: Basis, centres: np.ndarray, radius: float, partial_cells: bool = True) -> sp.csr_matrix:
    """`ball_average_operator` over the basis' quadrature points, about `centres` (n, 3) [m]
    (`surface_centres` for the body's surface), with the partial cells of `point_spacing`
    (or, partial_cells=False, the points inside only)."""
    if not radius > 0.0:
        raise ScenarioError("stress_radius", radius, "a positive radius [m]")
    spacing = point_spacing(basis) if partial_cells else 0.0
    return ball_average_operator(quadrature_points(basis), quadrature_weights(basis), centres, radius, spacing)

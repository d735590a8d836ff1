"""Stress recovery of the plate: plane-stress D, strains and stresses at the Gauss points.

Strains are (eps_xx, eps_yy, gamma_xy) with gamma_xy the engineering shear strain [-];
stresses (sigma_xx, sigma_yy, tau_xy) [Pa]; von Mises of plane stress is docs/model.md section 4.4, eq. 12.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp

if TYPE_CHECKING:  # pragma: no cover
    from skfem import Basis

#: Gauss order for K, M and stress recovery: 3 x 3 = 9 points per element.
INTORDER = 4


def plane_stress_matrix(E: float, nu: float) -> np.ndarray:
    """D = E / (1 - nu^2) [[1, nu, 0], [nu, 1, 0], [0, 0, (1 - nu) / 2]] [Pa].

    Acts on (eps_xx, eps_yy, gamma_xy) with gamma_xy the engineering shear strain.
    """
    return E / (1.0 - nu**2) * np.array([[1.0, nu, 0.0], [nu, 1.0, 0.0], [0.0, 0.0, 0.5 * (1.0 - nu)]])


def von_mises_plane_stress(sxx: np.ndarray, syy: np.ndarray, sxy: np.ndarray) -> np.ndarray:
    """sqrt(sxx^2 - sxx syy + syy^2 + 3 sxy^2) [Pa] (plane stress, szz = 0).

    Evaluated left to right in place (two temporaries, the same bits as the expression)."""
    sxx, syy, sxy = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (sxx, syy, sxy)))
    if sxx.ndim == 0:
        return np.sqrt(np.maximum(sxx**2 - sxx * syy + syy**2 + 3.0 * sxy**2, 0.0))
    total = sxx * sxx
    term = sxx * syy
    total -= term
    np.multiply(syy, syy, out=term)
    total += term
    np.multiply(sxy, sxy, out=term)
    term *= 3.0
    total += term
    np.maximum(total, 0.0, out=total)
    return np.sqrt(total, out=total)


def voigt_strain(grad: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(eps_xx, eps_yy, gamma_xy) from a displacement gradient grad[i, j] = du_i/dx_j."""
    return grad[0, 0], grad[1, 1], grad[0, 1] + grad[1, 0]


def strain_operator(basis: Basis) -> sp.csr_matrix:
    """Sparse map from the full dof vector to (eps_xx, eps_yy, gamma_xy) at the Gauss points.

    Shape (3 n_elem n_qp, n_full); row = component * n_elem * n_qp + element * n_qp + qp.
    """
    n_elem, n_qp = basis.dx.shape
    n_local = basis.element_dofs.shape[0]
    data = np.empty((3, n_local, n_elem, n_qp))
    cols = np.empty((n_local, n_elem, n_qp), dtype=np.int64)
    for i in range(n_local):
        exx, eyy, gxy = voigt_strain(basis.basis[i][0].grad)
        data[0, i], data[1, i], data[2, i] = exx, eyy, gxy
        cols[i] = basis.element_dofs[i][:, None]
    rows = (
        np.arange(3)[:, None, None, None] * (n_elem * n_qp)
        + np.arange(n_elem)[None, None, :, None] * n_qp
        + np.arange(n_qp)[None, None, None, :]
    )
    rows = np.broadcast_to(rows, data.shape)
    cols3 = np.broadcast_to(cols, data.shape)
    keep = data != 0.0
    op = sp.coo_matrix((data[keep], (rows[keep], cols3[keep])), shape=(3 * n_elem * n_qp, basis.N)).tocsr()
    op.sum_duplicates()
    op.sort_indices()
    return op


def quadrature_points(basis: Basis) -> np.ndarray:
    """Gauss point coordinates [m], (n_elem, n_qp, 2)."""
    return np.moveaxis(np.asarray(basis.mapping.F(basis.X)), 0, -1)


def gauss_point_strains(
    strain_op: sp.csr_matrix, x_full: np.ndarray, n_elem: int, n_qp: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """eps_xx, eps_yy, gamma_xy [-] at the Gauss points from x_full (..., n_full) [m].

    Each is (..., n_elem, n_qp); strain_op is `strain_operator`'s [component][element][qp] map.
    """
    flat = x_full.reshape(-1, strain_op.shape[1])
    eps = (strain_op @ flat.T).T  # (batch, 3 n_elem n_qp)
    eps = eps.reshape(x_full.shape[:-1] + (3, n_elem, n_qp))
    return eps[..., 0, :, :], eps[..., 1, :, :], eps[..., 2, :, :]


def plane_stresses(
    D: np.ndarray, exx: np.ndarray, eyy: np.ndarray, gxy: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """sigma_xx, sigma_yy, tau_xy = D (eps_xx, eps_yy, gamma_xy) [Pa], componentwise.

    Terms whose coefficient is zero (the shear coupling of an isotropic D) are left out:
    adding them changes no value (x + 0 = x)."""

    def row(i: int) -> np.ndarray:
        out = None
        for j, eps in enumerate((exx, eyy, gxy)):
            if D[i, j] == 0.0 and not (out is None and j == 2):
                continue
            term = D[i, j] * eps
            out = term if out is None else out + term
        return out

    return row(0), row(1), row(2)


# --------------------------------------------------------------------------------------
# The disc-averaged von Mises stress (docs/model.md section 4.4): a measure that converges
# --------------------------------------------------------------------------------------
#: Disc centres lie on a lattice whose spacing is this fraction of the disc radius [-].
DISC_CENTRE_SPACING = 0.25


def disc_centres(x0: float, y0: float, width: float, height: float, spacing: float) -> np.ndarray:
    """Centres [m] of the averaging discs, (n_centres, 2): a lattice over the plate
    [x0, x0 + width] x [y0, y0 + height], edges included, at most `spacing` [m] apart
    (the same points whatever the mesh)."""
    nx = int(np.ceil(width / spacing - 1e-9)) + 1
    ny = int(np.ceil(height / spacing - 1e-9)) + 1
    cx, cy = np.meshgrid(np.linspace(x0, x0 + width, nx), np.linspace(y0, y0 + height, ny), indexing="ij")
    return np.stack([cx.ravel(), cy.ravel()], axis=1)


def disc_average_operator(points: np.ndarray, weights: np.ndarray, centres: np.ndarray, radius: float) -> sp.csr_matrix:
    """Sparse (n_centres, n_points) map from values at the quadrature points to their
    mean over the disc of `radius` [m] about each centre, cut by the plate:
    row c = w_i [|x_i - c| <= radius] / sum of those w_i, the quadrature of
    (1 / |disc n plate|) integral of f over disc n plate.

    points: (n_points, 2) [m]; weights: (n_points,) quadrature weights [m^2]. A disc
    that holds no point (radius below the Gauss-point spacing) gets an empty row.
    """
    from scipy.spatial import cKDTree

    hits = cKDTree(points).query_ball_point(centres, radius)
    counts = np.fromiter((len(h) for h in hits), dtype=np.int64, count=len(hits))
    cols = np.concatenate([np.asarray(h, dtype=np.int64) for h in hits]) if counts.sum() else np.zeros(0, np.int64)
    rows = np.repeat(np.arange(len(hits)), counts)
    w = np.asarray(weights, dtype=float)[cols]
    total = np.bincount(rows, weights=w, minlength=len(hits))
    op = sp.csr_matrix((w / total[rows], (rows, cols)), shape=(len(hits), len(points)))
    op.sort_indices()
    return op


def max_disc_average(op: sp.csr_matrix, values: np.ndarray) -> np.ndarray:
    """Largest disc mean of `values` (..., n_points) over the discs of `op` -> (...)."""
    flat = values.reshape(-1, op.shape[1])
    return np.asarray((op @ flat.T).max(axis=0)).reshape(values.shape[:-1])

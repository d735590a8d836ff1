"""The plate's face (its left edge, facing the granules) and the patch contacts on it
(docs/model.md section 3.5).

A patch contact spreads its force as a uniform traction over [y_c - w/2, y_c + w/2]
(w the rigid-layer width, cut to the face), integrated with the face's quadratic Q8 edge
shape functions: the consistent nodal weights w_n(y_c), sum w_n = 1. The contact's
displacement is the same average of the face's, u_c = sum w_n u_n (x and y), so the
force's work on the plate is F . du_c: the transfer is work-consistent.

`patch_weights` is compiled: the time loop calls it when a patch moves.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from granplate.jit import njit

#: Gauss-Legendre 2-point rule on [-1, 1]: exact for the quadratic shape functions.
_GAUSS_X = 0.5773502691896257


def face_nodes(node_xy: np.ndarray, x0: float, tol: float) -> np.ndarray:
    """Indices of the nodes on the face x = x0 (+- tol) [m], sorted by y (bottom to top):
    element corners and mid-sides alternate, 2 ny + 1 nodes."""
    nodes = np.flatnonzero(np.abs(node_xy[:, 0] - x0) <= tol)
    return nodes[np.argsort(node_xy[nodes, 1], kind="stable")]


def face_rows(T: sp.spmatrix, nodes: np.ndarray) -> sp.csr_matrix:
    """(2 n_face, n_red) sparse 0/1: the rows of T at the face nodes' dofs, ordered [n0 x,
    n0 y, n1 x, ...] (empty at clamped nodes; a rigid layer's nodes copy its driving
    node). Face displacements are face_rows @ x_red; face forces f reach the reduced dofs
    as face_rows^T f."""
    dofs = np.stack([2 * nodes, 2 * nodes + 1], axis=1).ravel()
    return sp.csr_matrix(T)[dofs]


def face_modes(T: sp.spmatrix, Phi: np.ndarray, nodes: np.ndarray) -> np.ndarray:
    """(2 n_face, n_modes) mode shapes at the face nodes [kg^-1/2]: face_rows(T) @ Phi."""
    return np.ascontiguousarray(face_rows(T, nodes) @ Phi)


def face_forces(face_y: np.ndarray, patch_y: np.ndarray, width: float, force: np.ndarray) -> np.ndarray:
    """Nodal forces on the face's dofs [N] (..., 2 n_face), rows [n0 x, n0 y, ...], of
    patch contacts at heights patch_y (n_patch,) [m] of `width` [m] carrying `force`
    (..., 2 n_patch) [N] ordered [p0 x, p0 y, p1 x, ...]: each spread as w F."""
    patch_y = np.asarray(patch_y, dtype=float)
    W = (
        np.stack([patch_weight_vector(face_y, y, width) for y in patch_y])
        if len(patch_y)
        else np.zeros((0, len(face_y)))
    )
    f = np.asarray(force, dtype=float).reshape(np.shape(force)[:-1] + (len(patch_y), 2))
    nodal = np.einsum("kn,...kc->...nc", W, f)
    return nodal.reshape(nodal.shape[:-2] + (2 * len(face_y),))


@njit(cache=True)
def edge_shape_functions(xi):
    """The three quadratic shape functions of a Q8 edge (end, mid-side, end) at xi in [-1, 1]."""
    return 0.5 * xi * (xi - 1.0), 1.0 - xi * xi, 0.5 * xi * (xi + 1.0)


@njit(entry=True, cache=True)
def patch_weights(face_y, y_c, width, weights):
    """Consistent nodal weights of a patch of `width` [m] centred at y_c [m] on the face
    whose nodes lie at face_y (sorted; corners at even indices, mid-sides at odd ones):
    the uniform traction 1/L over the patch cut to the face (length L) integrated with
    the edge shape functions, so that sum(weights) = 1. A zero width (or a patch wholly
    off the face) gives the shape functions at y_c (cut to the face): a point load.

    Writes weights[first:last + 1] (the rest is left as it is) and returns (first, last).
    """
    n = face_y.shape[0]
    ne = (n - 1) // 2
    lo = max(y_c - 0.5 * width, face_y[0])
    hi = min(y_c + 0.5 * width, face_y[n - 1])
    if hi <= lo:  # a point load at y_c cut to the face
        yp = min(max(y_c, face_y[0]), face_y[n - 1])
        e = min(max(np.searchsorted(face_y, yp) - 1, 0) // 2, ne - 1)
        a = face_y[2 * e]
        b = face_y[2 * e + 2]
        n0, n1, n2 = edge_shape_functions(2.0 * (yp - a) / (b - a) - 1.0)
        weights[2 * e] = n0
        weights[2 * e + 1] = n1
        weights[2 * e + 2] = n2
        return 2 * e, 2 * e + 2
    e0 = min(max(np.searchsorted(face_y, lo, side="right") - 1, 0) // 2, ne - 1)
    e1 = min(max(np.searchsorted(face_y, hi, side="left") - 1, 0) // 2, ne - 1)
    for j in range(2 * e0, 2 * e1 + 3):
        weights[j] = 0.0
    scale = 1.0 / (hi - lo)
    for e in range(e0, e1 + 1):
        a = face_y[2 * e]
        b = face_y[2 * e + 2]
        s0 = max(lo, a)
        s1 = min(hi, b)
        if s1 <= s0:
            continue
        half = 0.5 * (s1 - s0)
        mid = 0.5 * (s1 + s0)
        for g in range(2):
            yq = mid + (_GAUSS_X if g == 1 else -_GAUSS_X) * half
            n0, n1, n2 = edge_shape_functions(2.0 * (yq - a) / (b - a) - 1.0)
            weights[2 * e] += n0 * half * scale
            weights[2 * e + 1] += n1 * half * scale
            weights[2 * e + 2] += n2 * half * scale
    return 2 * e0, 2 * e1 + 2


def patch_weight_vector(face_y: np.ndarray, y_c: float, width: float) -> np.ndarray:
    """(n_face,) the weights of `patch_weights` as a full vector (zeros elsewhere)."""
    w = np.zeros(len(face_y))
    patch_weights(np.asarray(face_y, float), float(y_c), float(width), w)
    return w

"""The closest point of a 3D solid's quadratic boundary faces to a sphere centre
(docs/model.md section 3.8), compiled: Newton in a face's reference coordinates, then its
edges and corners; the outward normal and signed distance there; and the search a patch
follows its granule with across faces (`slide_closest`, `follow_closest`: the face it last
touched and those sharing a corner with it), without Python per step.
"""

from __future__ import annotations

import numpy as np
from granplate.jit import njit

from granplate.solid.face_shapes import _QUAD_NODES, _TRI_NODES, TRI6, face_shape_functions, face_shape_hessians

#: Newton iterations of a projection, and its step tolerance in reference coordinates.
_NEWTON_ITERATIONS = 30
_NEWTON_TOL = 1e-14
#: How far inside its face's edges (in reference coordinates) a foot lets
#: `follow_closest` skip the neighbours.
INTERIOR = 1e-6
#: A foot on its face's edge lets `follow_closest` skip the neighbours when the centre lies
#: along the face's own normal there, to this cosine (1 - ALONG): the face's normal is then
#: the direction from the foot to the centre, a supporting plane of a convex body.
ALONG = 1e-12
#: A face lies within this factor times its largest node distance of its nodes' centroid
#: (room for the bulge of a curved quadratic face).
_BULGE = 1.25


@njit(cache=True)
def _face_curvature(X, kind, xi, eta, d2N, K):
    """K (3, 3): x_xixi, x_xieta, x_etaeta (columns) of the face at (xi, eta)."""
    face_shape_hessians(kind, xi, eta, d2N)
    for c in range(3):
        for m in range(3):
            K[c, m] = 0.0
            for k in range(X.shape[0]):
                K[c, m] += d2N[k, m] * X[k, c]


@njit(cache=True)
def _face_point(X, kind, xi, eta, N, dN, x, J):
    """x (3,) and its tangents J (3, 2) at (xi, eta) of the face with nodes X (n, 3) [m]."""
    face_shape_functions(kind, xi, eta, N, dN)
    for c in range(3):
        x[c] = 0.0
        J[c, 0] = 0.0
        J[c, 1] = 0.0
        for k in range(X.shape[0]):
            x[c] += N[k] * X[k, c]
            J[c, 0] += dN[k, 0] * X[k, c]
            J[c, 1] += dN[k, 1] * X[k, c]


@njit(cache=True)
def _distance2(X, kind, p, xi, eta, N, dN, x, J):
    _face_point(X, kind, xi, eta, N, dN, x, J)
    return (x[0] - p[0]) ** 2 + (x[1] - p[1]) ** 2 + (x[2] - p[2]) ** 2


@njit(cache=True)
def _inside(kind, xi, eta, tol):
    if kind == TRI6:
        return xi >= -tol and eta >= -tol and xi + eta <= 1.0 + tol
    return abs(xi) <= 1.0 + tol and abs(eta) <= 1.0 + tol


@njit(cache=True)
def _edge_ends(kind, e):
    """Reference coordinates (a_xi, a_eta, b_xi, b_eta) of the ends of the face's edge e."""
    if kind == TRI6:
        i = e
        j = (e + 1) % 3
        return _TRI_NODES[i, 0], _TRI_NODES[i, 1], _TRI_NODES[j, 0], _TRI_NODES[j, 1]
    i = e
    j = (e + 1) % 4
    return _QUAD_NODES[i, 0], _QUAD_NODES[i, 1], _QUAD_NODES[j, 0], _QUAD_NODES[j, 1]


@njit(entry=True, cache=True)
def face_closest(X, kind, p, out):
    """The closest point to p (3,) [m] on one face with nodes X (n, 3) [m].

    Newton (Gauss-Newton) on the squared distance in the face's reference coordinates, from
    the face's centre; where its minimum lies outside the face, the minimum over each edge
    (1D Newton clamped to the edge). Writes out[0:2] = (xi, eta), out[2:5] = the point [m];
    returns the squared distance [m^2].
    """
    n = X.shape[0]
    return _face_closest(
        X,
        kind,
        p,
        out,
        np.empty(n),
        np.empty((n, 2)),
        np.empty((n, 3)),
        np.empty(3),
        np.empty((3, 2)),
        np.empty((3, 3)),
    )


@njit(cache=True)
def _face_closest(X, kind, p, out, N, dN, d2N, x, J, K):
    """`face_closest` with its scratch passed in (N (n,), dN (n, 2), d2N (n, 3), x (3,),
    J (3, 2), K (3, 3)). Newton's Hessian includes the face's curvature (r . x_ab) where
    that keeps it positive definite, else the Gauss-Newton J^T J."""
    best = np.inf
    # the interior minimum
    xi = 1.0 / 3.0 if kind == TRI6 else 0.0
    eta = xi
    for _ in range(_NEWTON_ITERATIONS):
        _face_point(X, kind, xi, eta, N, dN, x, J)
        _face_curvature(X, kind, xi, eta, d2N, K)
        g0 = g1 = h00 = h01 = h11 = k00 = k01 = k11 = 0.0
        for c in range(3):
            r = x[c] - p[c]
            g0 += J[c, 0] * r
            g1 += J[c, 1] * r
            h00 += J[c, 0] * J[c, 0]
            h01 += J[c, 0] * J[c, 1]
            h11 += J[c, 1] * J[c, 1]
            k00 += r * K[c, 0]
            k01 += r * K[c, 1]
            k11 += r * K[c, 2]
        if h00 + k00 > 0.0 and (h00 + k00) * (h11 + k11) - (h01 + k01) ** 2 > 0.0:
            h00 += k00
            h01 += k01
            h11 += k11
        det = h00 * h11 - h01 * h01
        d0 = (h11 * g0 - h01 * g1) / det
        d1 = (h00 * g1 - h01 * g0) / det
        xi -= d0
        eta -= d1
        if abs(d0) + abs(d1) < _NEWTON_TOL or abs(xi) > 4.0 or abs(eta) > 4.0:
            break
    if _inside(kind, xi, eta, 1e-12):
        if kind == TRI6:
            xi = max(xi, 0.0)
            eta = max(eta, 0.0)
            s = xi + eta
            if s > 1.0:
                xi /= s
                eta /= s
        else:
            xi = min(max(xi, -1.0), 1.0)
            eta = min(max(eta, -1.0), 1.0)
        best = _distance2(X, kind, p, xi, eta, N, dN, x, J)
        out[0] = xi
        out[1] = eta
        for c in range(3):
            out[2 + c] = x[c]
        return best
    # the edges
    n_edges = 3 if kind == TRI6 else 4
    for e in range(n_edges):
        ax, ay, bx, by = _edge_ends(kind, e)
        tx = bx - ax
        ty = by - ay
        u = 0.5
        for _ in range(_NEWTON_ITERATIONS):
            _face_point(X, kind, ax + u * tx, ay + u * ty, N, dN, x, J)
            _face_curvature(X, kind, ax + u * tx, ay + u * ty, d2N, K)
            g = h = k = 0.0
            for c in range(3):
                tc = J[c, 0] * tx + J[c, 1] * ty
                g += tc * (x[c] - p[c])
                h += tc * tc
                k += (x[c] - p[c]) * (tx * tx * K[c, 0] + 2.0 * tx * ty * K[c, 1] + ty * ty * K[c, 2])
            step = g / (h + k) if h + k > 0.0 else g / h
            un = min(max(u - step, 0.0), 1.0)
            done = abs(un - u) < _NEWTON_TOL
            u = un
            if done:
                break
        d2 = _distance2(X, kind, p, ax + u * tx, ay + u * ty, N, dN, x, J)
        if d2 < best:
            best = d2
            out[0] = ax + u * tx
            out[1] = ay + u * ty
            for c in range(3):
                out[2 + c] = x[c]
    return best


@njit(entry=True, cache=True)
def face_normal(X, kind, xi, eta, normal):
    """The face's outward unit normal (x_xi x x_eta normalised) at (xi, eta), in place."""
    n = X.shape[0]
    N = np.empty(n)
    dN = np.empty((n, 2))
    x = np.empty(3)
    J = np.empty((3, 2))
    _face_point(X, kind, xi, eta, N, dN, x, J)
    normal[0] = J[1, 0] * J[2, 1] - J[2, 0] * J[1, 1]
    normal[1] = J[2, 0] * J[0, 1] - J[0, 0] * J[2, 1]
    normal[2] = J[0, 0] * J[1, 1] - J[1, 0] * J[0, 1]
    norm = np.sqrt(normal[0] ** 2 + normal[1] ** 2 + normal[2] ** 2)
    normal /= norm


@njit(entry=True, cache=True)
def contact_frame(X, kind, p, out):
    """From out[0:5] (face coordinates and closest point, `face_closest`) and the centre p:
    out[5:8] the outward unit normal, out[8] the signed distance [m] (positive outside).

    The distance is |p - x| with the sign of (p - x) . n_face; the normal is the unit
    vector from x to p turned outward (so at an edge or a corner it is the direction a
    sphere there is pushed), the face's own normal where p lies on the face."""
    nf = np.empty(3)
    face_normal(X, kind, out[0], out[1], nf)
    r0 = p[0] - out[2]
    r1 = p[1] - out[3]
    r2 = p[2] - out[4]
    d = np.sqrt(r0 * r0 + r1 * r1 + r2 * r2)
    sign = 1.0 if r0 * nf[0] + r1 * nf[1] + r2 * nf[2] >= 0.0 else -1.0
    size = 0.0
    for c in range(3):
        size = max(size, X[:, c].max() - X[:, c].min())
    if d > 1e-12 * size:
        out[5] = sign * r0 / d
        out[6] = sign * r1 / d
        out[7] = sign * r2 / d
    else:
        out[5:8] = nf
    out[8] = sign * d


@njit(cache=True)
def _lower_bound2(X, p):
    """A lower bound [m^2] of the squared distance from p to the face with nodes X: the
    distance to the nodes' centroid less the face's radius (`face_radius`), squared, or 0."""
    c0 = c1 = c2 = 0.0
    n = X.shape[0]
    for k in range(n):
        c0 += X[k, 0]
        c1 += X[k, 1]
        c2 += X[k, 2]
    c0 /= n
    c1 /= n
    c2 /= n
    r2 = 0.0
    for k in range(n):
        r2 = max(r2, (X[k, 0] - c0) ** 2 + (X[k, 1] - c1) ** 2 + (X[k, 2] - c2) ** 2)
    gap = np.sqrt((p[0] - c0) ** 2 + (p[1] - c1) ** 2 + (p[2] - c2) ** 2) - _BULGE * np.sqrt(r2)
    return gap * gap if gap > 0.0 else 0.0


@njit(cache=True, refcount=True)  # (its scratch arrays)
def slide_closest(nodes, kind, neighbours, face, p, out):
    """The closest point to p (3,) [m] on the surface near `face`: project onto the face and
    its neighbours (`face_neighbours`), move to the nearest, repeat until the face stays.

    nodes: (n_faces, n_nodes, 3) [m]; out (9,): (xi, eta), the point [m], the outward unit
    normal, the signed distance [m] (`contact_frame`). Returns the face. A small
    scratch per call, no Python. Exact while the centre moves less than
    about a face per call over a convex surface."""
    trial = np.empty(5)
    best_out = np.empty(5)
    n = nodes.shape[1]
    N = np.empty(n)
    dN = np.empty((n, 2))
    d2N = np.empty((n, 3))
    x = np.empty(3)
    J = np.empty((3, 2))
    K = np.empty((3, 3))
    best = _face_closest(nodes[face], kind, p, best_out, N, dN, d2N, x, J, K)
    for _ in range(nodes.shape[0]):
        moved = -1
        for j in range(neighbours.shape[1]):
            g = neighbours[face, j]
            if g < 0:
                break
            if _lower_bound2(nodes[g], p) >= best:
                continue
            d2 = _face_closest(nodes[g], kind, p, trial, N, dN, d2N, x, J, K)
            if d2 < best * (1.0 - 1e-12) - 1e-300:
                best = d2
                best_out[:] = trial
                moved = g
        if moved < 0:
            break
        face = moved
    out[0:5] = best_out
    contact_frame(nodes[face], kind, p, out)
    return face


@njit(entry=True, cache=True)
def follow_closest(nodes, kind, neighbours, face, p, out):
    """`slide_closest`, with a shortcut for a centre outside the body whose foot stays
    inside its face (reference coordinates within INTERIOR of the face's edges), or lies on
    its edge with the centre along the face's normal there (to ALONG: a contact on a line
    of nodes, as at the paper's rigid layers): that foot is the closest point of a convex
    body (a local minimum of the distance from outside a convex set is the global one;
    the face's normal at the foot is a supporting plane's), and no neighbour is projected.
    Returns the face (out as `slide_closest`'s). About a tenth of its cost on a face."""
    d2 = face_closest(nodes[face], kind, p, out)
    if d2 > 0.0:
        interior = _inside(kind, out[0], out[1], -INTERIOR)
        contact_frame(nodes[face], kind, p, out)
        if out[8] > 0.0 and (interior or _along_normal(nodes[face], kind, out)):
            return face
    return slide_closest(nodes, kind, neighbours, face, p, out)


@njit(refcount=True, cache=True)
def _along_normal(X, kind, out) -> bool:
    """Whether the unit direction out[5:8] from the foot (out[0:2]) to the centre is the
    face's own outward normal there, to ALONG (`contact_frame`'s output)."""
    nf = np.empty(3)
    face_normal(X, kind, out[0], out[1], nf)
    return out[5] * nf[0] + out[6] * nf[1] + out[7] * nf[2] >= 1.0 - ALONG

"""The boundary surface of a 3D solid as quadratic faces, and patch contacts on it
(docs/model.md section 3.8).

Each boundary facet of a scikit-fem mesh becomes a face with its quadratic nodes: quad8
(the trace of the 20-node serendipity hex, `ElementHexS2`), quad9 (the 27-node hex,
`ElementHex2`) or tri6 (the 10-node tet, `ElementTetP2`). The face is parametrised by
its own reference coordinates:

- quad8 / quad9: (xi, eta) in [-1, 1]^2; nodes ordered corners (-1,-1), (1,-1), (1,1),
  (-1,1), mid-sides (0,-1), (1,0), (0,1), (-1,0), then (quad9) the centre (0,0);
- tri6: (s, t) with s, t >= 0, s + t <= 1; nodes ordered corners (0,0), (1,0), (0,1),
  mid-sides (1/2,0), (1/2,1/2), (0,1/2).

The orientation is chosen per face so that x_xi x x_eta points out of the body. A face's
nodes carry the global dofs of the vector basis, `dofs[face, node, component]`, taken from
the element's dof layout (`basis.element_dofs`: local vector dof 3 j + c is component c of
scalar node j).

A point force F at a point of a face is spread over the face's nodes with the face's shape
functions at that point, f_(node, c) = N_node(xi) F_c: the weights sum to 1 and the nodal
forces' virtual work equals F . u(point) for every displacement of the element space
(whose trace on the face is spanned by these N). The compiled `slide_closest` moves a
patch with its granule: it projects the centre onto the patch's face and the faces that
share a corner with it, and walks to the nearest until it stays, so a patch crosses
faces, edges and corners without Python per step.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numba import njit

from granplate.errors import ScenarioError

#: Face kinds: the code the compiled functions take, and the nodes per face.
QUAD8, QUAD9, TRI6 = 0, 1, 2
KIND_NAMES = ("quad8", "quad9", "tri6")
NODES_PER_FACE = (8, 9, 6)

#: The face nodes' reference coordinates, in the order stated above.
_QUAD_NODES = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1], [0, -1], [1, 0], [0, 1], [-1, 0], [0, 0]], float)
_TRI_NODES = np.array([[0, 0], [1, 0], [0, 1], [0.5, 0], [0.5, 0.5], [0, 0.5]], float)

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


@dataclass(frozen=True)
class Surface:
    """The boundary faces of a solid.

    kind: QUAD8, QUAD9 or TRI6; facets, elements: (n_faces,) the mesh facet and the element
    it bounds; dofs: (n_faces, n_nodes, 3) global dofs of the vector basis; nodes:
    (n_faces, n_nodes, 3) the nodes' coordinates [m]; corners: (n_faces, n_corners) the
    mesh vertices at the face's corners.
    """

    kind: int
    facets: np.ndarray
    elements: np.ndarray
    dofs: np.ndarray
    nodes: np.ndarray
    corners: np.ndarray

    @property
    def n_faces(self) -> int:
        return len(self.facets)

    @cached_property
    def centroid_tree(self):
        """A k-d tree over the faces' node centroids (built on first use)."""
        from scipy.spatial import cKDTree

        return cKDTree(self.nodes.mean(axis=1))

    @cached_property
    def largest_radius(self) -> float:
        """The largest `face_radius` [m]."""
        return float(face_radius(self).max())


# --------------------------------------------------------------------------------------
# Shape functions of the faces (compiled)
# --------------------------------------------------------------------------------------
@njit(cache=True)
def face_shape_functions(kind, xi, eta, N, dN):
    """The face's shape functions N (n_nodes,) and their derivatives dN (n_nodes, 2) with
    respect to (xi, eta) at a reference point, written in place (node order of the module)."""
    if kind == TRI6:
        l0 = 1.0 - xi - eta
        N[0] = l0 * (2.0 * l0 - 1.0)
        N[1] = xi * (2.0 * xi - 1.0)
        N[2] = eta * (2.0 * eta - 1.0)
        N[3] = 4.0 * l0 * xi
        N[4] = 4.0 * xi * eta
        N[5] = 4.0 * eta * l0
        dN[0, 0] = 1.0 - 4.0 * l0
        dN[0, 1] = 1.0 - 4.0 * l0
        dN[1, 0] = 4.0 * xi - 1.0
        dN[1, 1] = 0.0
        dN[2, 0] = 0.0
        dN[2, 1] = 4.0 * eta - 1.0
        dN[3, 0] = 4.0 * (l0 - xi)
        dN[3, 1] = -4.0 * xi
        dN[4, 0] = 4.0 * eta
        dN[4, 1] = 4.0 * xi
        dN[5, 0] = -4.0 * eta
        dN[5, 1] = 4.0 * (l0 - eta)
        return
    if kind == QUAD9:  # tensor product of the 1D quadratic Lagrange functions
        ax = (0.5 * xi * (xi - 1.0), 1.0 - xi * xi, 0.5 * xi * (xi + 1.0))
        dax = (xi - 0.5, -2.0 * xi, xi + 0.5)
        ay = (0.5 * eta * (eta - 1.0), 1.0 - eta * eta, 0.5 * eta * (eta + 1.0))
        day = (eta - 0.5, -2.0 * eta, eta + 0.5)
        for k in range(9):
            i = int(_QUAD_NODES[k, 0]) + 1
            j = int(_QUAD_NODES[k, 1]) + 1
            N[k] = ax[i] * ay[j]
            dN[k, 0] = dax[i] * ay[j]
            dN[k, 1] = ax[i] * day[j]
        return
    for k in range(4):  # quad8 serendipity: corners
        a = _QUAD_NODES[k, 0]
        b = _QUAD_NODES[k, 1]
        s = 1.0 + a * xi
        t = 1.0 + b * eta
        q = a * xi + b * eta - 1.0
        N[k] = 0.25 * s * t * q
        dN[k, 0] = 0.25 * a * t * (q + s)
        dN[k, 1] = 0.25 * b * s * (q + t)
    for k in range(4, 8):  # mid-sides
        a = _QUAD_NODES[k, 0]
        b = _QUAD_NODES[k, 1]
        if a == 0.0:
            N[k] = 0.5 * (1.0 - xi * xi) * (1.0 + b * eta)
            dN[k, 0] = -xi * (1.0 + b * eta)
            dN[k, 1] = 0.5 * b * (1.0 - xi * xi)
        else:
            N[k] = 0.5 * (1.0 + a * xi) * (1.0 - eta * eta)
            dN[k, 0] = 0.5 * a * (1.0 - eta * eta)
            dN[k, 1] = -eta * (1.0 + a * xi)


@njit(cache=True)
def face_shape_hessians(kind, xi, eta, d2N):
    """The shape functions' second derivatives d2N (n_nodes, 3): (xi xi, xi eta, eta eta)."""
    if kind == TRI6:
        d2N[:, :] = 0.0
        d2N[0, 0] = d2N[0, 1] = d2N[0, 2] = 4.0
        d2N[1, 0] = 4.0
        d2N[2, 2] = 4.0
        d2N[3, 0] = -8.0
        d2N[3, 1] = -4.0
        d2N[4, 1] = 4.0
        d2N[5, 1] = -4.0
        d2N[5, 2] = -8.0
        return
    if kind == QUAD9:
        ax = (0.5 * xi * (xi - 1.0), 1.0 - xi * xi, 0.5 * xi * (xi + 1.0))
        dax = (xi - 0.5, -2.0 * xi, xi + 0.5)
        ay = (0.5 * eta * (eta - 1.0), 1.0 - eta * eta, 0.5 * eta * (eta + 1.0))
        day = (eta - 0.5, -2.0 * eta, eta + 0.5)
        dd = (1.0, -2.0, 1.0)
        for k in range(9):
            i = int(_QUAD_NODES[k, 0]) + 1
            j = int(_QUAD_NODES[k, 1]) + 1
            d2N[k, 0] = dd[i] * ay[j]
            d2N[k, 1] = dax[i] * day[j]
            d2N[k, 2] = ax[i] * dd[j]
        return
    for k in range(4):
        a = _QUAD_NODES[k, 0]
        b = _QUAD_NODES[k, 1]
        s = 1.0 + a * xi
        t = 1.0 + b * eta
        d2N[k, 0] = 0.5 * t
        d2N[k, 1] = 0.25 * a * b * (a * xi + b * eta - 1.0 + s + t)
        d2N[k, 2] = 0.5 * s
    for k in range(4, 8):
        a = _QUAD_NODES[k, 0]
        b = _QUAD_NODES[k, 1]
        if a == 0.0:
            d2N[k, 0] = -(1.0 + b * eta)
            d2N[k, 1] = -xi * b
            d2N[k, 2] = 0.0
        else:
            d2N[k, 0] = 0.0
            d2N[k, 1] = -eta * a
            d2N[k, 2] = -(1.0 + a * xi)


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


@njit(cache=True)
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
        out[2:5] = x
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
            out[2:5] = x
    return best


@njit(cache=True)
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


@njit(cache=True)
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


@njit(cache=True)
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


@njit(cache=True)
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


@njit(cache=True)
def _along_normal(X, kind, out) -> bool:
    """Whether the unit direction out[5:8] from the foot (out[0:2]) to the centre is the
    face's own outward normal there, to ALONG (`contact_frame`'s output)."""
    nf = np.empty(3)
    face_normal(X, kind, out[0], out[1], nf)
    return out[5] * nf[0] + out[6] * nf[1] + out[7] * nf[2] >= 1.0 - ALONG


# --------------------------------------------------------------------------------------
# Extraction (Python, once per mesh)
# --------------------------------------------------------------------------------------
def _kind_of(element) -> int:
    """The face kind of a scikit-fem scalar element (hex20, hex27, tet10)."""
    name = type(element).__name__
    kinds = {"ElementHexS2": QUAD8, "ElementHex2": QUAD9, "ElementTetP2": TRI6}
    if name not in kinds:
        raise ScenarioError(
            "solid.element", name, "one of ElementHexS2 (hex20), ElementHex2 (hex27), ElementTetP2 (tet10)"
        )
    return kinds[name]


def _reference_faces(kind: int, doflocs: np.ndarray) -> list[tuple[np.ndarray, np.ndarray, tuple]]:
    """Per local face of the reference element: (its local vertex indices, its local scalar
    dofs in the module's node order, the affine map (origin, axis_s, axis_t) from the face's
    reference coordinates to the element's).

    The hex reference is [0, 1]^3 (a face: one coordinate 0 or 1, (xi, eta) = 2 (the other
    two) - 1), the tet's the unit simplex (faces x = 0, y = 0, z = 0, x + y + z = 1)."""
    faces = []
    if kind == TRI6:
        planes = [
            (lambda q: q[:, 2], np.array([0, 0, 0.0]), np.array([1, 0, 0.0]), np.array([0, 1, 0.0])),
            (lambda q: q[:, 1], np.array([0, 0, 0.0]), np.array([1, 0, 0.0]), np.array([0, 0, 1.0])),
            (lambda q: q[:, 0], np.array([0, 0, 0.0]), np.array([0, 1, 0.0]), np.array([0, 0, 1.0])),
            (lambda q: 1.0 - q.sum(axis=1), np.array([0, 0, 1.0]), np.array([1, 0, -1.0]), np.array([0, 1, -1.0])),
        ]
        ref = _TRI_NODES
        n_vertices = 4
    else:
        planes = []
        for a in range(3):
            b, c = [i for i in range(3) if i != a]
            for v in (0.0, 1.0):
                origin = np.full(3, 0.5)
                origin[a] = v
                es = np.zeros(3)
                es[b] = 0.5
                et = np.zeros(3)
                et[c] = 0.5
                planes.append((lambda q, a=a, v=v: q[:, a] - v, origin, es, et))
        ref = _QUAD_NODES[: NODES_PER_FACE[kind]]
        n_vertices = 8
    for level, origin, es, et in planes:
        on = np.flatnonzero(np.abs(level(doflocs)) < 1e-12)
        order = []
        for r in ref:
            target = origin + r[0] * es + r[1] * et
            order.append(on[np.argmin(np.linalg.norm(doflocs[on] - target, axis=1))])
        order = np.array(order)
        assert np.allclose(doflocs[order], origin + ref[:, :1] * es + ref[:, 1:] * et)
        vertices = np.sort(on[on < n_vertices])
        faces.append((vertices, order, (origin, es, et)))
    return faces


def _swap_order(kind: int) -> np.ndarray:
    """The node permutation that swaps the face's two reference coordinates (flips the
    normal): new node k is old node perm[k]."""
    ref = _TRI_NODES if kind == TRI6 else _QUAD_NODES[: NODES_PER_FACE[kind]]
    swapped = ref[:, ::-1]
    return np.array([int(np.argmin(np.linalg.norm(ref - s, axis=1))) for s in swapped])


def boundary_surface(basis, groups: tuple[str, ...] | None = None) -> Surface:
    """The boundary faces of the solid of a scikit-fem vector basis (`ElementVector` of
    `ElementHexS2`, `ElementHex2` or `ElementTetP2` on `MeshHex` / `MeshTet`), all of them
    or those of the named facet groups (`mesh.boundaries`), outward oriented."""
    mesh = basis.mesh
    element = getattr(basis.elem, "elem", None)
    if element is None or getattr(basis.elem, "dim", None) != 3:
        raise ScenarioError(
            "solid.element", type(basis.elem).__name__, "a 3-component ElementVector of a quadratic solid element"
        )
    kind = _kind_of(element)
    if groups is None:
        facets = mesh.boundary_facets()
    else:
        named = mesh.boundaries or {}
        unknown = [g for g in groups if g not in named]
        if unknown:
            raise ScenarioError("solid.surface_groups", unknown, f"facet groups of the mesh: {sorted(named)}")
        facets = np.unique(np.concatenate([np.asarray(named[g]) for g in groups]))
        inner = facets[mesh.f2t[1, facets] >= 0]
        if len(inner):
            raise ScenarioError(
                "solid.surface_groups",
                list(groups),
                f"groups of boundary facets (facets {inner[:5].tolist()} are inside the body)",
            )
    facets = np.asarray(facets, dtype=np.int64)
    elements = mesh.f2t[0, facets].astype(np.int64)
    ref_faces = _reference_faces(kind, np.asarray(element.doflocs, float))
    swap = _swap_order(kind)
    n_nodes = NODES_PER_FACE[kind]
    dofs = np.empty((len(facets), n_nodes, 3), dtype=np.int64)
    lookup = {tuple(v.tolist()): (order, amap) for v, order, amap in ref_faces}
    elem_dofs = basis.element_dofs
    for i, (f, e) in enumerate(zip(facets, elements)):
        local = np.sort(np.flatnonzero(np.isin(mesh.t[:, e], mesh.facets[:, f])))
        order, _ = lookup[tuple(local.tolist())]
        for c in range(3):
            dofs[i, :, c] = elem_dofs[3 * order + c, e]
    nodes = np.ascontiguousarray(np.moveaxis(basis.doflocs[:, dofs[:, :, 0]], 0, -1))
    # outward orientation: x_xi x x_eta against the element's centre
    centres = mesh.p[:, mesh.t[:, elements]].mean(axis=1).T
    n_corner = 3 if kind == TRI6 else 4
    normal = np.empty(3)
    for i in range(len(facets)):
        face_normal(nodes[i], kind, *((1 / 3, 1 / 3) if kind == TRI6 else (0.0, 0.0)), normal)
        if normal @ (nodes[i, :n_corner].mean(axis=0) - centres[i]) < 0.0:
            dofs[i] = dofs[i, swap]
            nodes[i] = nodes[i, swap]
    corners = np.ascontiguousarray(dofs[:, :n_corner, 0])
    return Surface(kind=kind, facets=facets, elements=elements, dofs=dofs, nodes=nodes, corners=corners)


def face_neighbours(surface: Surface) -> np.ndarray:
    """(n_faces, max_neighbours) int64: the faces that share a corner with each face, padded
    with -1 (built once; `slide_closest` walks on it)."""
    touching: dict[int, list[int]] = {}
    for f, corners in enumerate(surface.corners):
        for v in corners:
            touching.setdefault(int(v), []).append(f)
    lists = []
    for f, corners in enumerate(surface.corners):
        near = sorted({g for v in corners for g in touching[int(v)]} - {f})
        lists.append(near)
    width = max((len(n) for n in lists), default=0)
    table = np.full((surface.n_faces, max(width, 1)), -1, dtype=np.int64)
    for f, near in enumerate(lists):
        table[f, : len(near)] = near
    return table


def face_radius(surface: Surface) -> np.ndarray:
    """(n_faces,) a bound on each face's distance from its nodes' centroid [m]: the largest
    node distance, enlarged by a quarter for the bulge of a curved quadratic face."""
    centroid = surface.nodes.mean(axis=1)
    return _BULGE * np.linalg.norm(surface.nodes - centroid[:, None, :], axis=2).max(axis=1)


@dataclass(frozen=True)
class ClosestPoint:
    """The closest point of the surface to a centre: face, reference coordinates xi (2,),
    point [m] (3,), outward unit normal (3,), signed distance [m] (positive outside)."""

    face: int
    xi: np.ndarray
    point: np.ndarray
    normal: np.ndarray
    distance: float


def closest_point(surface: Surface, point) -> ClosestPoint:
    """The closest point of the whole surface to `point` (3,) [m]: candidate faces from a
    k-d tree over the face centroids (every face whose centroid lies within the first
    face's distance plus the largest face radius), projected each by `face_closest`."""
    p = np.asarray(point, dtype=float).ravel()
    if p.shape != (3,) or not np.all(np.isfinite(p)):
        raise ScenarioError("point", point, "three finite coordinates [m]")
    tree = surface.centroid_tree
    _, first = tree.query(p)
    scratch = np.empty(9)
    bound = np.sqrt(face_closest(surface.nodes[first], surface.kind, p, scratch))
    candidates = tree.query_ball_point(p, bound + surface.largest_radius)
    best, best_face, best_out = np.inf, -1, np.empty(9)
    for f in sorted(candidates):
        d2 = face_closest(surface.nodes[f], surface.kind, p, scratch)
        if d2 < best:
            best, best_face, best_out = d2, f, scratch.copy()
    contact_frame(surface.nodes[best_face], surface.kind, p, best_out)
    return ClosestPoint(
        face=int(best_face),
        xi=best_out[0:2].copy(),
        point=best_out[2:5].copy(),
        normal=best_out[5:8].copy(),
        distance=float(best_out[8]),
    )


def patch_weights(surface: Surface, face: int, xi) -> tuple[np.ndarray, np.ndarray]:
    """The consistent weights of a point force at reference point xi (2,) of `face`:
    (dofs (n_nodes, 3), weights (n_nodes,)); the nodal force on dofs[k, c] is
    weights[k] F_c [N]. The weights are the face's shape functions at xi: they sum to 1 and
    the nodal forces' work equals F . u(point) for every displacement of the element space."""
    n = NODES_PER_FACE[surface.kind]
    N = np.empty(n)
    dN = np.empty((n, 2))
    face_shape_functions(surface.kind, float(xi[0]), float(xi[1]), N, dN)
    return surface.dofs[face], N

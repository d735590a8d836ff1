"""The shape functions of a 3D solid's quadratic boundary faces (docs/model.md section 3.8):
quad8 (the trace of the 20-node serendipity hex), quad9 (the 27-node hex) and tri6 (the
10-node tet), in the face's own reference coordinates and node order (solid/surface.py),
with their first and second derivatives, compiled.
"""

from __future__ import annotations

import numpy as np
from granplate.jit import njit

#: Face kinds: the code the compiled functions take, and the nodes per face.
QUAD8, QUAD9, TRI6 = 0, 1, 2
KIND_NAMES = ("quad8", "quad9", "tri6")
NODES_PER_FACE = (8, 9, 6)

#: The face nodes' reference coordinates, in the order stated above.
_QUAD_NODES = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1], [0, -1], [1, 0], [0, 1], [-1, 0], [0, 0]], float)
_TRI_NODES = np.array([[0, 0], [1, 0], [0, 1], [0.5, 0], [0.5, 0.5], [0, 0.5]], float)


@njit(entry=True, cache=True)
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

"""The nodal forces of point contact forces on the solid's surface, over a run.

A granule touching boundary face f at its reference point xi with the force F [N] on the
body loads the face's nodes with f_(node, c) = N_node(xi) F_c (`surface.patch_weights`:
the work-consistent weights, the face's shape functions). Summed over the granules, one
row per output time, on the reduced dofs (a dof held by a clamp or a roller takes no
load: its reaction balances it).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from granplate.jit import njit

from granplate.solid.surface import NODES_PER_FACE, Surface, face_shape_functions


@njit(entry=True, cache=True)
def _weights(kind, xi, n_nodes):
    """(n_c, n_nodes) the face's shape functions at each contact's point xi (n_c, 2)."""
    w = np.empty((xi.shape[0], n_nodes))
    N = np.empty(n_nodes)
    dN = np.empty((n_nodes, 2))
    for c in range(xi.shape[0]):
        face_shape_functions(kind, xi[c, 0], xi[c, 1], N, dN)
        w[c, :] = N
    return w


def nodal_force_history(
    surface: Surface, dofs: np.ndarray, n_full: int, face: np.ndarray, xi: np.ndarray, force: np.ndarray
) -> sp.csr_matrix:
    """(n_t, n_red) [N]: the nodal forces on the reduced dofs at each output time.

    surface: the boundary faces (`surface.boundary_surface`); dofs (n_red,): the full dof
    of each reduced dof (`SolidModel.dofs`) of the n_full; face (n_t, n_g) int: the face
    each granule touches (-1: none); xi (n_t, n_g, 2): its reference point there; force
    (n_t, n_g, 3) [N]: the force on the body."""
    face = np.asarray(face, np.int64)
    n_t, n_g = face.shape
    xi = np.asarray(xi, float).reshape(n_t, n_g, 2)
    force = np.asarray(force, float).reshape(n_t, n_g, 3)
    if face.size and (face.max() >= surface.n_faces or face.min() < -1):
        raise ValueError(f"contact faces must lie in -1 .. {surface.n_faces - 1}")
    n_nodes = NODES_PER_FACE[surface.kind]
    t, g = np.nonzero(face >= 0)
    w = _weights(surface.kind, np.ascontiguousarray(xi[t, g]), n_nodes)  # (n_c, n_nodes)
    full = surface.dofs[face[t, g]]  # (n_c, n_nodes, 3) full dofs
    values = w[:, :, None] * force[t, g][:, None, :]  # (n_c, n_nodes, 3)
    to_reduced = np.full(n_full, -1, np.int64)
    to_reduced[np.asarray(dofs, np.int64)] = np.arange(len(dofs))
    cols = to_reduced[full].ravel()
    rows = np.repeat(t, n_nodes * 3)
    keep = cols >= 0
    out = sp.coo_matrix((values.ravel()[keep], (rows[keep], cols[keep])), shape=(n_t, len(dofs))).tocsr()
    out.sum_duplicates()
    out.eliminate_zeros()
    return out

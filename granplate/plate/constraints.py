"""Constraints of the plate: edges, clamps, symmetry line, rigid layers, the reduction T.

A full displacement vector is x_full = T @ x_red: clamped dofs are removed and every
node of a contact's rigid layer copies its driving node's dofs (a multi-point
constraint); a matrix A reduces to T^T A T.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Sequence

import numpy as np
import scipy.sparse as sp

from granplate.plate.errors import plate_inputs
from granplate.setup.plate_checks import NODE_RTOL, PLATE_EDGES, check_clamped_edges, check_symmetry_row, rigid_layers

if TYPE_CHECKING:  # pragma: no cover
    from granplate.setup.scenario import Plate

#: Relative tolerance (times the plate height / width) for "a node lies at this coordinate"
#: (the one validation uses to put contacts on nodes).
GEOMETRY_RTOL = NODE_RTOL

EDGES = PLATE_EDGES


def nodes_on_line(node_xy: np.ndarray, axis: int, value: float, tol: float) -> np.ndarray:
    """Indices of the nodes whose coordinate `axis` (0: x, 1: y) is value +- tol."""
    return np.flatnonzero(np.abs(node_xy[:, axis] - value) <= tol)


def edge_nodes(node_xy: np.ndarray, plate: "Plate", x0: float) -> dict[str, np.ndarray]:
    """Node indices on each of the four plate edges ("top", "bottom", "left", "right")."""
    tx, ty = GEOMETRY_RTOL * plate.width, GEOMETRY_RTOL * plate.height
    return {
        "left": nodes_on_line(node_xy, 0, x0, tx),
        "right": nodes_on_line(node_xy, 0, x0 + plate.width, tx),
        "bottom": nodes_on_line(node_xy, 1, plate.y0, ty),
        "top": nodes_on_line(node_xy, 1, plate.y0 + plate.height, ty),
    }


def clamped_dofs(node_xy: np.ndarray, plate: "Plate", x0: float) -> np.ndarray:
    """Sorted full-dof indices fixed by plate.clamped_edges (both dofs of every edge node)."""
    with plate_inputs():
        check_clamped_edges(plate)
    edges = edge_nodes(node_xy, plate, x0)
    nodes = np.unique(np.concatenate([edges[e] for e in plate.clamped_edges] + [np.empty(0, np.int64)]))
    return np.sort(np.concatenate([2 * nodes, 2 * nodes + 1])).astype(np.int64)


def symmetry_line_nodes(node_xy: np.ndarray, plate: "Plate") -> np.ndarray:
    """Nodes on y = y0 + height / 2, sorted by x; requires an even plate.ny."""
    with plate_inputs():
        check_symmetry_row(plate)
    nodes = nodes_on_line(node_xy, 1, plate.y0 + 0.5 * plate.height, GEOMETRY_RTOL * plate.height)
    return nodes[np.argsort(node_xy[nodes, 0], kind="stable")]


def rigid_layer_nodes(
    node_xy: np.ndarray, plate: "Plate", x0: float, contact_y: Sequence[float]
) -> tuple[np.ndarray, list[np.ndarray]]:
    """Driving node and layer nodes of each contact on the left edge x = x0.

    Returns (driving, layers): driving[k] is the left-edge node at y_k; layers[k] the
    other left-edge nodes with |y - y_k| <= w/2 (w = plate.layer_width), which move
    with it. Raises PlateError for a contact off the plate, between nodes, or
    layers that overlap.
    """
    left = edge_nodes(node_xy, plate, x0)["left"]
    with plate_inputs():
        found = rigid_layers(plate, contact_y, node_xy[left, 1])
    driving = np.array([left[at] for at, _ in found], dtype=np.int64)
    layers = [left[np.asarray(members, dtype=np.int64)] for _, members in found]
    return driving, layers


def rigid_layer_map(
    n_full: int, fixed: np.ndarray, driving: np.ndarray, layers: Sequence[np.ndarray]
) -> tuple[sp.csr_matrix, np.ndarray]:
    """The reduction x_full = T x_red and the reduced indices of the driving dofs.

    Reduced dofs are the full dofs that are neither fixed nor slaved, in increasing
    order. A slaved node's x (y) dof copies its driving node's x (y) dof. Driving and
    slaved nodes must be free (see setup.plate_checks.check_layers_off_clamps). Returns T (n_full, n_red)
    and drive_dofs (n_contacts, 2).
    """
    master = np.arange(n_full)
    free = np.ones(n_full, dtype=bool)
    free[fixed] = False
    for d, members in zip(driving, layers):
        if not free[2 * d] or any(not free[2 * n] for n in members):
            raise ValueError("rigid-layer nodes must be free and belong to one layer only")
        for n in members:
            for c in (0, 1):
                master[2 * n + c] = 2 * d + c
                free[2 * n + c] = False
    reduced_of_full = np.full(n_full, -1, dtype=np.int64)
    reduced_of_full[free] = np.arange(int(free.sum()))
    rows = np.flatnonzero(free | (master != np.arange(n_full)))
    cols = reduced_of_full[master[rows]]
    T = sp.csr_matrix((np.ones(rows.size), (rows, cols)), shape=(n_full, int(free.sum())))
    drive_dofs = np.stack([reduced_of_full[2 * driving], reduced_of_full[2 * driving + 1]], axis=1)
    return T, drive_dofs.reshape(-1, 2).astype(np.int64)


def reduce_matrix(A: sp.spmatrix, T: sp.spmatrix) -> sp.csr_matrix:
    """T^T A T, symmetrised exactly."""
    Ar = (T.T @ A @ T).tocsr()
    return ((Ar + Ar.T) * 0.5).tocsr()

"""The surface nodes a contact's disc patch averages (docs/model.md section 3.9): each
node's share of the surface, a grid of cells over them (the compiled search of the nodes
within a patch, solver.body.disc_patch), how many nodes a patch can hold, and the
smallest radius whose every patch holds one."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from granplate.errors import ScenarioError
from granplate.solid.surface import Surface, face_shape_functions


class SurfaceNodes(NamedTuple):
    """The boundary's nodes."""

    face_snode: np.ndarray  # (n_faces, n_fn) int64: each face node's surface node
    full: np.ndarray  # (n_sn,) int64: its node of the mesh (full dofs 3 n + c)
    xyz: np.ndarray  # (n_sn, 3) [m]
    area: np.ndarray  # (n_sn,) [m^2]: its share of the surface (each face's area shared equally by its nodes)


class NodeGrid(NamedTuple):
    """Surface nodes cell by cell on a grid of cubes of side `cell`."""

    cell: float
    origin: np.ndarray  # (3,) [m]
    shape: np.ndarray  # (3,) int64
    start: np.ndarray  # (n_cells + 1,) int64
    nodes: np.ndarray  # (n_sn,) int64


def face_areas(surface: Surface) -> np.ndarray:
    """(n_faces,) [m^2] each face's area (Gauss quadrature of |x_xi x x_eta|)."""
    from granplate.solid.surface import TRI6

    n = surface.nodes.shape[1]
    if surface.kind == TRI6:
        pts = np.array([[1 / 6, 1 / 6], [2 / 3, 1 / 6], [1 / 6, 2 / 3]])
        wts = np.full(3, 1 / 6)
    else:
        g = np.sqrt(3.0 / 5.0)
        x = np.array([-g, 0.0, g])
        w = np.array([5.0, 8.0, 5.0]) / 9.0
        pts = np.array([[a, b] for a in x for b in x])
        wts = np.array([wa * wb for wa in w for wb in w])
    N = np.empty(n)
    dN = np.empty((n, 2))
    areas = np.zeros(surface.n_faces)
    for (xi, eta), wq in zip(pts, wts):
        face_shape_functions(surface.kind, float(xi), float(eta), N, dN)
        J = np.einsum("fnc,nk->fck", surface.nodes, dN)
        areas += wq * np.linalg.norm(np.cross(J[:, :, 0], J[:, :, 1]), axis=1)
    return areas


def surface_nodes(surface: Surface) -> SurfaceNodes:
    """The boundary's nodes, their coordinates and shares of the surface."""
    full_of = surface.dofs[:, :, 0] // 3
    full, inverse = np.unique(full_of.ravel(), return_inverse=True)
    face_snode = inverse.reshape(full_of.shape).astype(np.int64)
    xyz = np.zeros((len(full), 3))
    xyz[face_snode.ravel()] = surface.nodes.reshape(-1, 3)
    area = np.zeros(len(full))
    np.add.at(area, face_snode.ravel(), np.repeat(face_areas(surface) / full_of.shape[1], full_of.shape[1]))
    return SurfaceNodes(face_snode=face_snode, full=full.astype(np.int64), xyz=xyz, area=area)


def node_grid(xyz: np.ndarray, cell: float, max_cells: int = 1 << 22) -> NodeGrid:
    """The nodes xyz (n, 3) on a grid of cubes of side at least `cell` [m] (widened so that
    the grid has at most max_cells cells)."""
    lo = xyz.min(axis=0) - 1e-9
    extent = xyz.max(axis=0) - lo + 1e-9
    cell = float(max(cell, (float(np.prod(extent)) / max_cells) ** (1.0 / 3.0)))
    shape = np.maximum(np.ceil(extent / cell).astype(np.int64), 1)
    idx = np.minimum(((xyz - lo) / cell).astype(np.int64), shape - 1)
    cid = (idx[:, 0] * shape[1] + idx[:, 1]) * shape[2] + idx[:, 2]
    order = np.argsort(cid, kind="stable")
    start = np.searchsorted(cid[order], np.arange(int(np.prod(shape)) + 1)).astype(np.int64)
    return NodeGrid(cell=cell, origin=lo, shape=shape, start=start, nodes=order.astype(np.int64))


def farthest_from_nodes(surface: Surface, xyz: np.ndarray) -> float:
    """About the largest distance [m] from a point of the surface to its nearest surface
    node: over each face's centre and the midpoints between its nodes."""
    from scipy.spatial import cKDTree

    nodes = surface.nodes
    probes = [nodes.mean(axis=1)]
    n = nodes.shape[1]
    for a in range(n):
        for b in range(a + 1, n):
            probes.append(0.5 * (nodes[:, a] + nodes[:, b]))
    d, _ = cKDTree(xyz).query(np.concatenate(probes))
    return float(d.max())


def patch_capacity(xyz: np.ndarray, radius: float, reach: float) -> int:
    """The most surface nodes within `radius` [m] of any surface point: at most those
    within radius + reach of a node (reach: the farthest a surface point lies from a node)."""
    from scipy.spatial import cKDTree

    tree = cKDTree(xyz)
    return int(max(len(n) for n in tree.query_ball_point(xyz, radius + reach)))


#: A disc patch's radius is at least this times the farthest a surface point lies from a node.
MIN_PATCH_RATIO = 1.5


def check_patch_radius(radius: float, reach: float) -> None:
    """ScenarioError("plate.patch_radius") for a disc patch too small for the mesh: some
    patch would hold no node, or one node alone."""
    smallest = MIN_PATCH_RATIO * reach
    if 0.0 < radius < smallest:
        raise ScenarioError(
            "plate.patch_radius",
            radius,
            f"must be 0 (a point patch) or at least {smallest:.4g} m on this mesh: "
            f"{MIN_PATCH_RATIO:g} x the farthest a point of the surface lies from a node "
            f"({reach:.4g} m), so that every patch averages several nodes; refine the mesh for "
            "a smaller patch",
        )

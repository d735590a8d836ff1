"""Rigid patches tied to a solid's surface (`plate.rigid_patches`, docs/model.md section
3.9): the 3D analogue of the paper's rigid layers. The surface nodes within a patch's
radius of its centre move as one rigid body: a penalty kappa C on their dofs, C = I - Q Q^T
the projector off the patch's six rigid motions (Q an orthonormal basis of them), added to
K. A deformation of the patch costs kappa times its squared norm, a rigid motion nothing;
kappa = PENALTY x the largest diagonal entry of K there, so the patch's own deformation is
about 1/PENALTY of the surface's under the same load, and its stiffest modes lie far above
any cut-off (their static response is the residual compliance's)."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from granplate.errors import ScenarioError

#: The tie's stiffness against the largest diagonal entry of K at the patch's dofs.
PENALTY = 1.0e4
#: Surface nodes a patch must hold (a rigid motion is fixed by three nodes not on a line).
MIN_NODES = 3


def patch_distance(points: np.ndarray, centre, axis=None) -> np.ndarray:
    """(n,) the distance [m] of each point (n, 3) [m] from a patch: from its centre (a disc,
    axis None), or from the line through the centre along `axis` (a strip)."""
    d = np.asarray(points, float).reshape(-1, 3) - np.asarray(centre, float)
    if axis is not None:
        a = np.asarray(axis, float) / np.linalg.norm(axis)
        d = d - np.outer(d @ a, a)
    return np.linalg.norm(d, axis=1)


def in_patch(points: np.ndarray, patch) -> np.ndarray:
    """(n,) bool: which points (n, 3) [m] lie on the rigid patch (setup.scenario.RigidPatch)."""
    return patch_distance(points, patch.centre, patch.axis) <= patch.radius


def patch_nodes(
    surface_xyz: np.ndarray, surface_full: np.ndarray, centre, radius: float, index: int, axis=None
) -> np.ndarray:
    """The mesh nodes (full ids) of the surface nodes within `radius` [m] of `centre` [m]
    (of the line through it along `axis`, when given); ScenarioError naming
    plate.rigid_patches[index] when fewer than MIN_NODES."""
    d = patch_distance(surface_xyz, centre, axis)
    nodes = surface_full[d <= radius]
    if len(nodes) < MIN_NODES:
        raise ScenarioError(
            f"plate.rigid_patches[{index}]",
            {"centre": list(centre), "radius": radius},
            f"holds {len(nodes)} surface node(s): a rigid patch needs at least {MIN_NODES}; "
            f"move its centre onto the surface or widen its radius (the nearest surface node is "
            f"{d.min():.4g} m from the centre)",
        )
    return np.sort(nodes)


#: A face faces a patch when its normal lies within 60 degrees of the patch's (cosine).
FACING_COSINE = 0.5


def facing_nodes(surface, centre) -> tuple[np.ndarray, np.ndarray]:
    """(xyz (n, 3) [m], full node ids (n,)) of the surface nodes on the faces that face the
    same way as the face closest to `centre` (normals within 60 degrees): a patch ties the
    face it lies on and its continuation, not the faces round an edge (a strip across a
    slab's thickness would otherwise reach into its side faces)."""
    from granplate.solid.surface import TRI6, closest_point, face_normal

    n0 = closest_point(surface, centre).normal
    mid = 1.0 / 3.0 if surface.kind == TRI6 else 0.0  # the face's centre in its reference coordinates
    normal = np.empty(3)
    keep = np.zeros(surface.n_faces, bool)
    for f in range(surface.n_faces):
        face_normal(surface.nodes[f], surface.kind, mid, mid, normal)
        keep[f] = float(normal @ n0) > FACING_COSINE
    full = surface.dofs[keep, :, 0] // 3
    xyz = surface.nodes[keep]
    ids, first = np.unique(full.ravel(), return_index=True)
    return xyz.reshape(-1, 3)[first], ids.astype(np.int64)


def rigid_basis(xyz: np.ndarray, rotates: bool = True) -> np.ndarray:
    """(3 n, 6) an orthonormal basis of the rigid motions of the points xyz (n, 3): three
    translations and three rotations about their centroid (dof 3 a + c); (3 n, 3) the
    translations alone when not `rotates` (the paper's rigid layer)."""
    r = xyz - xyz.mean(axis=0)
    n = len(xyz)
    R = np.zeros((3 * n, 6))
    for c in range(3):
        R[c::3, c] = 1.0
    R[1::3, 3], R[2::3, 3] = -r[:, 2], r[:, 1]  # about x: (0, -z, y)
    R[0::3, 4], R[2::3, 4] = r[:, 2], -r[:, 0]  # about y: (z, 0, -x)
    R[0::3, 5], R[1::3, 5] = -r[:, 1], r[:, 0]  # about z: (-y, x, 0)
    if not rotates:
        R = R[:, :3]
    Q, s, _ = np.linalg.svd(R, full_matrices=False)
    return Q[:, s > 1e-12 * s.max()]


def tie_penalty(
    K: sp.spmatrix, xyz_nodes: np.ndarray, patches: list[np.ndarray], rotates: list[bool] | None = None
) -> sp.csr_matrix:
    """The penalties of the rigid patches (each an array of mesh nodes; rotates[k]: whether
    patch k may rotate, default all) on the full dofs of K (nodes' coordinates xyz_nodes
    (n_nodes, 3) [m]), as a sparse matrix to add to K."""
    K = sp.csr_matrix(K)
    diag = K.diagonal()
    rows, cols, vals = [], [], []
    for k, nodes in enumerate(patches):
        dofs = (3 * nodes[:, None] + np.arange(3)).ravel()
        Q = rigid_basis(xyz_nodes[nodes], True if rotates is None else bool(rotates[k]))
        C = np.eye(len(dofs)) - Q @ Q.T
        kappa = PENALTY * float(diag[dofs].max())
        r, c = np.meshgrid(dofs, dofs, indexing="ij")
        rows.append(r.ravel())
        cols.append(c.ravel())
        vals.append((kappa * C).ravel())
    if not rows:
        return sp.csr_matrix(K.shape)
    return sp.coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=K.shape).tocsr()

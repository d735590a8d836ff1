"""The solid's supports: clamped faces (every dof fixed), rollers (the dof along the
face's normal fixed), free elsewhere; and the reduced system's dof map.

A roller's face must be flat and normal to a coordinate axis (a box's faces are); its
normal is that axis.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
import scipy.sparse as sp
from skfem import Basis, Mesh

from granplate.errors import ScenarioError
from granplate.solid.mesh import face_facets

#: A face is axis-aligned when its normals' other components stay below this.
AXIS_RTOL = 1e-6


def face_nodes(sbasis: Basis, mesh: Mesh, name: str, field: str) -> np.ndarray:
    """The sorted nodes (scalar basis dofs: corners and mid-nodes) on a named face."""
    return np.unique(sbasis.get_dofs(face_facets(mesh, name, field)).all())


def face_node_dofs(sbasis: Basis, mesh: Mesh, name: str, field: str) -> np.ndarray:
    """(n_face_nodes, 3) dofs [x, y, z] of the nodes on a named face, by node index."""
    return 3 * face_nodes(sbasis, mesh, name, field)[:, None] + np.arange(3)


def face_normal_axis(mesh: Mesh, name: str, field: str) -> int:
    """The coordinate axis a flat, axis-aligned face is normal to (ScenarioError naming
    `field` when the face is not)."""
    facets = face_facets(mesh, name, field)
    p = mesh.p[:, mesh.facets[:, facets]]  # (3, corners, n)
    normal = np.cross((p[:, 1] - p[:, 0]).T, (p[:, 2] - p[:, 0]).T)
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    axis = int(np.argmax(np.abs(normal).sum(axis=0)))
    off = np.delete(np.abs(normal), axis, axis=1).max()
    if off > AXIS_RTOL:
        raise ScenarioError(
            field,
            name,
            f"a roller's face must be flat and normal to x, y or z (this one's normals tilt by up to {off:.3g})",
        )
    return axis


def fixed_dofs(sbasis: Basis, mesh: Mesh, clamped: Sequence[str] = (), rollers: Sequence[str] = ()) -> np.ndarray:
    """The sorted fixed dofs of the vector system on a scalar basis' nodes: every dof of
    the clamped faces' nodes, the normal dof of the rollers' nodes (fields plate.clamped,
    plate.rollers)."""
    parts = [face_node_dofs(sbasis, mesh, name, "plate.clamped").ravel() for name in clamped]
    for name in rollers:
        axis = face_normal_axis(mesh, name, "plate.rollers")
        parts.append(face_node_dofs(sbasis, mesh, name, "plate.rollers")[:, axis])
    return np.unique(np.concatenate(parts)) if parts else np.zeros(0, dtype=np.int64)


def free_dofs(n_dofs: int, fixed: np.ndarray) -> np.ndarray:
    """The reduced system's dof map: full index of each reduced dof (ascending)."""
    return np.setdiff1d(np.arange(n_dofs), fixed)


def reduced(A: sp.spmatrix, dofs: np.ndarray) -> sp.csc_matrix:
    """A[dofs][:, dofs] (csc)."""
    A = sp.csr_matrix(A)
    return sp.csc_matrix(A[dofs][:, dofs])


def reduced_index(dofs: np.ndarray, full: np.ndarray) -> np.ndarray:
    """Positions in the reduced system of full dofs (-1 for fixed ones)."""
    where = np.searchsorted(dofs, full)
    where = np.minimum(where, len(dofs) - 1)
    return np.where(dofs[where] == full, where, -1)

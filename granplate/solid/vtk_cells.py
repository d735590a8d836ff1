"""The solid's elements as VTK cells: each element's nodes in VTK's order.

VTK numbers a cell's nodes by their place in its reference cell (parametric coordinates
r, s, t in [0, 1]^3, or the unit simplex), which is not scikit-fem's local dof order
(`ElementHexS2`, `ElementHex2`: the reference corner 0 at (1, 1, 1); mid-edge dofs in
scikit-fem's edge order). `VTK_REFERENCE` lists VTK's nodes:

- hex20, VTK_QUADRATIC_HEXAHEDRON (meshio "hexahedron20"): corners 0-7 at (0,0,0),
  (1,0,0), (1,1,0), (0,1,0), then the same at t = 1; mid-edges 8-19 on the edges (0,1),
  (1,2), (2,3), (3,0), (4,5), (5,6), (6,7), (7,4), (0,4), (1,5), (2,6), (3,7);
- hex27, VTK_TRIQUADRATIC_HEXAHEDRON ("hexahedron27"): those 20, the face centres 20-25
  on r = 0, r = 1, s = 0, s = 1, t = 0, t = 1, the centre 26 (vtkTriQuadraticHexahedron);
- tet10, VTK_QUADRATIC_TETRA ("tetra10"): corners 0-3 at (0,0,0), (1,0,0), (0,1,0),
  (0,0,1); mid-edges 4-9 on (0,1), (1,2), (2,0), (0,3), (1,3), (2,3).

Each VTK node is matched to the scikit-fem dof at the same reference point (the element's
`doflocs`), so the physical node is the same point of the element map. VTK's cells are
positively oriented (the corners 0, 1, 3 and 4 of a hex, 0, 1, 2 and 3 of a tet, a
right-handed frame); an element whose map reverses orientation takes the order of the
mirrored reference (r and s swapped), checked per element from its corners.
"""

from __future__ import annotations

import numpy as np

#: The element names' meshio cell types.
MESHIO_CELLS = {"hex20": "hexahedron20", "hex27": "hexahedron27", "tet10": "tetra10"}

_HEX_CORNERS = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], float)
_HEX_EDGES = ((0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4), (0, 4), (1, 5), (2, 6), (3, 7))
_HEX_FACES = np.array([[0, 0.5, 0.5], [1, 0.5, 0.5], [0.5, 0, 0.5], [0.5, 1, 0.5], [0.5, 0.5, 0], [0.5, 0.5, 1]])
_TET_CORNERS = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
_TET_EDGES = ((0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3))


def _with_edges(corners: np.ndarray, edges) -> np.ndarray:
    return np.vstack([corners, [(corners[a] + corners[b]) / 2 for a, b in edges]])


#: VTK's reference nodes (n, 3) per element name (module docstring).
VTK_REFERENCE: dict[str, np.ndarray] = {
    "hex20": _with_edges(_HEX_CORNERS, _HEX_EDGES),
    "hex27": np.vstack([_with_edges(_HEX_CORNERS, _HEX_EDGES), _HEX_FACES, [[0.5, 0.5, 0.5]]]),
    "tet10": _with_edges(_TET_CORNERS, _TET_EDGES),
}
#: The corners spanning a cell's frame at corner 0 (VTK order): a hex's 1, 3, 4, a tet's 1, 2, 3.
_FRAME = {"hex20": (1, 3, 4), "hex27": (1, 3, 4), "tet10": (1, 2, 3)}


def reference_order(element: str, doflocs: np.ndarray, mirrored: bool = False) -> np.ndarray:
    """The scikit-fem local dof (its reference point doflocs (n_local, 3)) at each of VTK's
    nodes of `element`; mirrored: of VTK's reference with r and s swapped."""
    ref = VTK_REFERENCE[element]
    if mirrored:
        ref = ref[:, [1, 0, 2]]
    dist = np.linalg.norm(np.asarray(doflocs, float)[None, :, :] - ref[:, None, :], axis=2)
    order = np.argmin(dist, axis=1)
    if not (np.allclose(dist[np.arange(len(ref)), order], 0.0) and len(set(order.tolist())) == len(ref)):
        raise ValueError(f"the element's dofs do not sit at VTK's {element} nodes")
    return order


def frame_volume(nodes: np.ndarray, element: str) -> np.ndarray:
    """det[x_a - x_0, x_b - x_0, x_c - x_0] [m^3] of each cell's frame at corner 0
    (`_FRAME`), nodes (n_cells, n, 3) in VTK order: positive for VTK's orientation."""
    a, b, c = _FRAME[element]
    x0 = nodes[:, 0]
    return np.linalg.det(np.stack([nodes[:, a] - x0, nodes[:, b] - x0, nodes[:, c] - x0], axis=-1))


def vtk_connectivity(sbasis, element: str) -> np.ndarray:
    """(n_elem, n_local) int64: each element's nodes (the scalar basis' dofs, = the solid's
    node indices) in VTK's order for `element` (module docstring)."""
    doflocs = np.asarray(sbasis.elem.doflocs, float)
    dofs = np.asarray(sbasis.element_dofs, np.int64).T  # (n_elem, n_local)
    xyz = np.asarray(sbasis.doflocs, float).T
    cells = dofs[:, reference_order(element, doflocs)]
    flipped = frame_volume(xyz[cells], element) < 0.0
    if flipped.any():
        cells[flipped] = dofs[flipped][:, reference_order(element, doflocs, mirrored=True)]
    return np.ascontiguousarray(cells)


#: Each VTK cell's faces by their corners in order around the face: VTK's faces of
#: vtkHexahedron and vtkTetra, outward (right-handed) for a positively oriented cell.
VTK_FACES = {
    "hex": ((0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)),
    "tet": ((0, 2, 1), (0, 1, 3), (1, 2, 3), (0, 3, 2)),
}


def boundary_faces(cells: np.ndarray, element: str) -> tuple[np.ndarray, np.ndarray]:
    """The faces of VTK-ordered cells (n_cells, n) that only one cell has (the body's
    boundary): (corner nodes (n_faces, 3 or 4) in order around the face, the cell of each)."""
    local = np.array(VTK_FACES["tet" if element == "tet10" else "hex"])  # (faces per cell, k)
    corners = np.asarray(cells)[:, local]  # (n_cells, f, k)
    flat = corners.reshape(-1, local.shape[1])
    _, first, counts = np.unique(np.sort(flat, axis=1), axis=0, return_index=True, return_counts=True)
    keep = np.sort(first[counts == 1])
    return flat[keep], keep // local.shape[0]

"""The solid's mesh: a box of hexahedra or tetrahedra, or a mesh file read through
meshio, as a linear scikit-fem mesh (MeshHex1, MeshTet1: the quadratic element adds the
mid-nodes) with named facet groups (`mesh.boundaries`).

A box names its six faces xmin, xmax, ymin, ymax, zmin, zmax. A file (Gmsh .msh) names
its surfaces by physical groups of quadrilaterals (hexahedra) or triangles (tetrahedra).
Every problem is a ScenarioError naming the field (`plate.mesh`, `plate.size`, ...).
"""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

import numpy as np
from skfem import Mesh, MeshHex, MeshTet

from granplate.errors import ScenarioError

#: The faces of a box, named by the coordinate and side they lie on.
BOX_FACES: tuple[str, ...] = ("xmin", "xmax", "ymin", "ymax", "zmin", "zmax")
#: The cell types a mesh file may hold (linear cells; the element supplies mid-nodes).
FILE_CELLS: dict[str, str] = {"hexahedron": "quad", "tetra": "triangle"}
#: Reference coordinates of the 8 corners of a hexahedron in meshio/VTK order.
VTK_HEX_CORNERS = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]])
#: An element whose smallest corner Jacobian is below this share of the mean element's
#: volume is degenerate.
DEGENERATE_RTOL = 1e-8


def face_axis(name: str) -> int:
    """The coordinate (0, 1, 2) normal to a box face ('xmin' -> 0)."""
    return "xyz".index(name[0])


def box_mesh(
    size: Sequence[float], elements: Sequence[int], origin: Sequence[float] = (0.0, 0.0, 0.0), tetrahedra: bool = False
) -> Mesh:
    """A box [origin, origin + size] [m] of nx x ny x nz hexahedra (tetrahedra: each cube
    cut into tetrahedra) with its six faces named (BOX_FACES)."""
    axes = [np.linspace(o, o + s, int(n) + 1) for o, s, n in zip(origin, size, elements)]
    mesh = (MeshTet if tetrahedra else MeshHex).init_tensor(*axes)
    tol = 1e-9 * max(size)
    faces = {}
    for name in BOX_FACES:
        axis = face_axis(name)
        plane = origin[axis] + (size[axis] if name.endswith("max") else 0.0)
        faces[name] = lambda x, a=axis, c=plane: np.abs(x[a] - c) < tol
    return mesh.with_boundaries(faces)


def corner_jacobians(points: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """Signed Jacobian determinants [m^3] at each corner of each cell, (n_cells, n_corners):
    tetrahedra (4 nodes) or hexahedra (8 nodes, VTK order); positive for a valid cell."""
    p = points[cells]
    if cells.shape[1] == 4:
        d = np.linalg.det(np.stack([p[:, 1] - p[:, 0], p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]], axis=-1))
        return d[:, None]
    out = np.empty(cells.shape[:1] + (8,))
    for k, ref in enumerate(VTK_HEX_CORNERS):
        cols, sign = [], 1.0
        for axis in range(3):
            other = ref.copy()
            other[axis] = 1 - other[axis]
            j = int(np.flatnonzero((VTK_HEX_CORNERS == other).all(axis=1))[0])
            cols.append(p[:, j] - p[:, k])
            sign *= 1.0 if ref[axis] == 0 else -1.0
        out[:, k] = sign * np.linalg.det(np.stack(cols, axis=-1))
    return out


def check_cells(points: np.ndarray, cells: np.ndarray, field: str, value: object) -> None:
    """ScenarioError naming `field` for an inverted (negative corner Jacobian) or
    degenerate (near-zero) cell."""
    jac = corner_jacobians(points, cells)
    scale = np.abs(jac).mean()
    bad = np.flatnonzero(jac.min(axis=1) <= DEGENERATE_RTOL * scale)
    if bad.size:
        c = int(bad[0])
        kind = "inverted" if jac[c].min() < -DEGENERATE_RTOL * scale else "degenerate"
        raise ScenarioError(
            field,
            value,
            f"{bad.size} cell(s) are inverted or degenerate (first: cell {c}, "
            f"{kind}, smallest corner Jacobian {jac[c].min():.3g} m^3 against a mean of "
            f"{scale:.3g}); fix the mesh's node order or shape",
        )


def _read(path: Path, field: str):
    """meshio's mesh of a file (ScenarioError when it cannot be read)."""
    import meshio

    if not path.is_file():
        raise ScenarioError(field, str(path), "no such file: give a mesh file (Gmsh .msh) that exists")
    try:
        return meshio.read(str(path))
    except (Exception, SystemExit) as exc:  # meshio raises many kinds, and exits on a file of no known format
        why = "" if isinstance(exc, SystemExit) else f" ({type(exc).__name__}: {exc})"
        raise ScenarioError(
            field, str(path), f"cannot be read as a mesh{why}; give a Gmsh .msh file of hexahedra or tetrahedra"
        ) from None


def _group_facets(
    m, mesh: Mesh, surface_type: str, field: str, path: str, surface: np.ndarray | None = None
) -> dict[str, np.ndarray]:
    """The named facet groups of a file: its physical groups of surface cells (surface:
    those cells renumbered as the mesh's points; None: as the file has them), mapped to
    the facets of the skfem mesh."""
    lookup = {tuple(f): i for i, f in enumerate(np.sort(mesh.facets, axis=0).T)}
    groups: dict[str, np.ndarray] = {}
    physical = m.cell_data_dict.get("gmsh:physical", {})
    if surface_type not in physical:
        return groups
    tags = physical[surface_type]
    surface = m.cells_dict[surface_type] if surface is None else surface
    for name, (tag, dim) in m.field_data.items():
        if int(dim) != 2:
            continue
        facets = []
        for cell in surface[tags == tag]:
            f = lookup.get(tuple(np.sort(cell)))
            if f is None:
                raise ScenarioError(
                    field, path, f"surface group {name!r} has a {surface_type} that is not a face of the volume cells"
                )
            facets.append(f)
        groups[str(name)] = np.array(sorted(facets), dtype=np.int64)
    return groups


def read_mesh(path: str | Path, field: str = "plate.mesh") -> Mesh:
    """A mesh file (Gmsh .msh, read by meshio) -> a skfem MeshHex or MeshTet with its
    physical surface groups as named boundaries. One cell type per file: hexahedron or
    tetra (linear cells; quadratic files are refused: the element adds the mid-nodes)."""
    from skfem.io.meshio import INV_HEX_MAPPING

    path = Path(path)
    m = _read(path, field)
    found = [c for c in m.cells_dict if c in FILE_CELLS]
    if not found:
        raise ScenarioError(
            field,
            str(path),
            f"holds no supported volume cells (found {sorted(m.cells_dict)}); "
            "allowed: " + " or ".join(FILE_CELLS) + " (linear cells: the element "
            "supplies the mid-nodes)",
        )
    if len(found) > 1:
        raise ScenarioError(field, str(path), "holds both hexahedra and tetrahedra; one cell type per mesh")
    cell_type = found[0]
    cells = np.asarray(m.cells_dict[cell_type], dtype=np.int64)
    used = np.unique(cells)
    points = np.asarray(m.points, dtype=float)
    if points.shape[1] != 3:
        raise ScenarioError(field, str(path), "points must have three coordinates")
    check_cells(points, cells, field, str(path))
    t = cells.T[INV_HEX_MAPPING[:8]] if cell_type == "hexahedron" else cells.T
    surface = None
    if used.size != points.shape[0]:  # drop geometry points no cell uses; renumber (meshio's
        renumber = -np.ones(points.shape[0], dtype=np.int64)  # cells_dict is a fresh dict per call)
        renumber[used] = np.arange(used.size)
        points, t = points[used], renumber[t]
        surface = renumber[np.asarray(m.cells_dict.get(FILE_CELLS[cell_type], np.zeros((0, 3), int)), dtype=np.int64)]
    mesh = (MeshHex if cell_type == "hexahedron" else MeshTet)(np.ascontiguousarray(points.T), np.ascontiguousarray(t))
    groups = _group_facets(m, mesh, FILE_CELLS[cell_type], field, str(path), surface)
    return mesh.with_boundaries(groups) if groups else mesh


def face_names(mesh: Mesh) -> tuple[str, ...]:
    """The mesh's named facet groups."""
    return tuple(sorted(mesh.boundaries or {}))


def face_facets(mesh: Mesh, name: str, field: str) -> np.ndarray:
    """The facets of a named face (ScenarioError naming `field` when it does not exist)."""
    groups = mesh.boundaries or {}
    if name not in groups:
        raise ScenarioError(
            field, name, "no such face; the mesh names: " + (", ".join(repr(n) for n in sorted(groups)) or "none")
        )
    return np.asarray(groups[name], dtype=np.int64)


#: Two boundary facets that share an edge meet at a crease, drawn in an outline, when
#: their normals differ by more than this angle [degrees].
CREASE_DEGREES = 20.0


def facet_normals(mesh: Mesh, facets: np.ndarray) -> np.ndarray:
    """(n, 3) unit normals of boundary facets, pointing out of the body: the direction of
    least spread of each facet's vertices (a plane fitted through them), turned away from
    the centre of the cell it bounds."""
    pts = mesh.p[:, mesh.facets[:, facets]].transpose(2, 1, 0)  # (n, vertices, 3)
    centred = pts - pts.mean(axis=1, keepdims=True)
    normals = np.linalg.svd(centred)[2][:, -1, :]
    cells = mesh.f2t[0, facets]
    outward = pts.mean(axis=1) - mesh.p[:, mesh.t[:, cells]].mean(axis=1).T
    return normals * np.sign(np.sum(normals * outward, axis=1))[:, None]


def boundary_polygons(mesh: Mesh) -> np.ndarray:
    """(n, k, 3) the corners [m] of every boundary facet (k = 4 quadrilaterals, 3
    triangles), in order around the facet (by angle about its centre in its plane): the
    body's surface as polygons, for a drawing to fill."""
    facets = mesh.boundary_facets()
    pts = mesh.p[:, mesh.facets[:, facets]].transpose(2, 1, 0)
    if len(facets) == 0:
        return pts
    centre = pts.mean(axis=1, keepdims=True)
    normals = facet_normals(mesh, facets)
    a = pts[:, 0] - centre[:, 0]
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    b = np.cross(normals, a)
    rel = pts - centre
    angle = np.arctan2(np.sum(rel * b[:, None], axis=2), np.sum(rel * a[:, None], axis=2))
    order = np.argsort(angle, axis=1)
    return np.ascontiguousarray(np.take_along_axis(pts, order[:, :, None], axis=1))


def outline_edges(mesh: Mesh, facets: np.ndarray | None = None) -> np.ndarray:
    """(n, 2, 3) the end points [m] of the edges that outline a set of boundary facets (all
    boundary facets by default): an edge of the set's facets where only one of them has
    it (the set's border), or where the two that share it meet at a crease (normals apart
    by more than CREASE_DEGREES): a box's 12 edges, a face's 4."""
    facets = mesh.boundary_facets() if facets is None else np.asarray(facets, dtype=np.int64)
    if len(facets) == 0:
        return np.zeros((0, 2, 3))
    normals = facet_normals(mesh, facets)
    edges = mesh.f2e[:, facets]  # (edges per facet, n)
    owners: dict[int, list[int]] = {}
    for k in range(edges.shape[1]):
        for e in edges[:, k]:
            owners.setdefault(int(e), []).append(k)
    cos_crease = np.cos(np.radians(CREASE_DEGREES))
    drawn = sorted(e for e, ks in owners.items() if len(ks) != 2 or float(normals[ks[0]] @ normals[ks[1]]) < cos_crease)
    ends = mesh.edges[:, np.array(drawn, dtype=np.int64)]  # (2, n)
    return np.ascontiguousarray(mesh.p[:, ends].transpose(2, 1, 0))

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

The compiled parts have modules of their own, their names importable from here too: the
faces' shape functions (`face_shapes`) and the closest-point search (`closest`).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from granplate.errors import ScenarioError
from granplate.solid.closest import _BULGE, contact_frame, face_closest, face_normal
from granplate.solid.face_shapes import _QUAD_NODES, _TRI_NODES, NODES_PER_FACE, QUAD8, QUAD9, TRI6

# the compiled pieces, in modules of their own, importable from here as before
from granplate.solid.closest import ALONG as ALONG, INTERIOR as INTERIOR
from granplate.solid.closest import follow_closest as follow_closest, slide_closest as slide_closest
from granplate.solid.face_shapes import KIND_NAMES as KIND_NAMES
from granplate.solid.face_shapes import face_shape_functions as face_shape_functions
from granplate.solid.face_shapes import face_shape_hessians as face_shape_hessians


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

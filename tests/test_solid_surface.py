"""The solid's boundary surface (granplate.solid.surface) against geometry: feet of
perpendiculars, distances to edges and corners, exact interpolation by the face weights,
and the sliding projection against the brute-force closest point."""

from __future__ import annotations

import numpy as np
import pytest
from skfem import Basis, ElementHex2, ElementHexS2, ElementTetP2, ElementVector, MeshHex, MeshTet

from granplate.errors import ScenarioError
from granplate.solid.surface import (
    QUAD8,
    QUAD9,
    TRI6,
    boundary_surface,
    closest_point,
    face_closest,
    face_neighbours,
    follow_closest,
    patch_weights,
    slide_closest,
)

#: The unit cube [0, 1]^3 meshed in 2 x 2 x 2 hexes or 48 tets, with each quadratic element.
ELEMENTS = {
    "hex20": (MeshHex, ElementHexS2, QUAD8),
    "hex27": (MeshHex, ElementHex2, QUAD9),
    "tet10": (MeshTet, ElementTetP2, TRI6),
}


def cube_basis(name: str, refine: int = 1) -> Basis:
    mesh_type, element, _ = ELEMENTS[name]
    return Basis(mesh_type().refined(refine), ElementVector(element()))


@pytest.fixture(scope="module", params=list(ELEMENTS))
def cube(request):
    basis = cube_basis(request.param)
    return request.param, basis, boundary_surface(basis)


def brute_force(surface, p, tie=1e-9):
    """The closest point over all faces, one at a time: (squared distance, the points of
    every face within `tie` [m] of the smallest distance: the ties at an edge or a medial
    plane)."""
    out = np.empty(9)
    found = []
    for f in range(surface.n_faces):
        d2 = face_closest(surface.nodes[f], surface.kind, p, out)
        found.append((d2, out[2:5].copy()))
    best = min(d2 for d2, _ in found)
    return best, [x for d2, x in found if np.sqrt(d2) - np.sqrt(best) < tie]


def test_faces_cover_the_cube_outward(cube):
    """The faces are the cube's 6 sides, their areas sum to 6 and every normal points out."""
    name, basis, s = cube
    assert s.kind == ELEMENTS[name][2]
    assert s.n_faces == (24 if name != "tet10" else 48)
    centroid = s.nodes.mean(axis=1)
    for f in range(s.n_faces):
        cp = closest_point(s, centroid[f] + 0.1 * (centroid[f] - 0.5) / np.abs(centroid[f] - 0.5).max())
        assert np.isclose(cp.distance, 0.1, atol=1e-12)
        axis = np.argmax(np.abs(centroid[f] - 0.5))
        assert np.isclose(cp.normal[axis], np.sign(centroid[f][axis] - 0.5))
    # the dofs are the basis' own: their locations are the nodes, component c at dofs[..., c]
    assert np.allclose(basis.doflocs[:, s.dofs[..., 1]], np.moveaxis(s.nodes, -1, 0))
    # and the same dofs as scikit-fem's own facet dofs of the boundary
    assert set(s.dofs.ravel()) == set(np.asarray(basis.get_dofs(s.facets).flatten()))


def test_foot_of_a_point_above_a_face(cube):
    """A point above the top side projects to its foot, at its height, normal +z."""
    _, _, s = cube
    cp = closest_point(s, [0.3, 0.4, 1.7])
    assert np.allclose(cp.point, [0.3, 0.4, 1.0], atol=1e-13)
    assert np.isclose(cp.distance, 0.7) and np.allclose(cp.normal, [0, 0, 1], atol=1e-13)
    inside = closest_point(s, [0.3, 0.4, 0.9])
    assert np.isclose(inside.distance, -0.1) and np.allclose(inside.normal, [0, 0, 1], atol=1e-13)


def test_edge_and_corner(cube):
    """Outside an edge the closest point is on the edge, at the distance in the normal plane;
    outside a corner it is the corner, at the distance to it; the normal points to the centre."""
    _, _, s = cube
    edge = closest_point(s, [1.3, 0.45, 1.4])
    assert np.allclose(edge.point, [1.0, 0.45, 1.0], atol=1e-12)
    assert np.isclose(edge.distance, 0.5)
    assert np.allclose(edge.normal, [0.6, 0.0, 0.8], atol=1e-12)
    corner = closest_point(s, [-0.2, 1.1, -0.2])
    assert np.allclose(corner.point, [0.0, 1.0, 0.0], atol=1e-12)
    assert np.isclose(corner.distance, 0.3)


def test_weights_interpolate_quadratic_fields(cube):
    """The weights are the face's shape functions: they sum to 1 and reproduce a linear and a
    quadratic field (in the element space) exactly at the point, so sum_k w_k F . u_k = F . u."""
    _, _, s = cube
    rng = np.random.default_rng(1)
    fields = (
        lambda x: 1.0 + 2.0 * x[..., 0] - 3.0 * x[..., 1] + 0.5 * x[..., 2],
        lambda x: x[..., 0] ** 2 - 2.0 * x[..., 1] * x[..., 2] + x[..., 0] * x[..., 1] + x[..., 2],
    )
    for _ in range(10):
        p = rng.uniform(-0.3, 1.3, 3)
        cp = closest_point(s, p)
        dofs, w = patch_weights(s, cp.face, cp.xi)
        assert dofs.shape == (len(w), 3)
        assert np.isclose(w.sum(), 1.0, atol=1e-14)
        for u in fields:
            assert np.isclose(w @ u(s.nodes[cp.face]), u(cp.point), atol=1e-13)


def box_basis(name: str) -> Basis:
    """The box [0, 2] x [0, 1] x [0, 0.5] in 4 x 2 x 2 hexes (or those cut into tets)."""
    mesh_type, element, _ = ELEMENTS[name]
    mesh = mesh_type.init_tensor(np.linspace(0, 2, 5), np.linspace(0, 1, 3), np.linspace(0, 0.5, 3))
    return Basis(mesh, ElementVector(element()))


@pytest.mark.parametrize("follow", [False, True])
@pytest.mark.parametrize("name", ["hex20", "tet10"])
def test_sliding_projection_equals_brute_force(name, follow):
    """A seeded random walk around a box (outside and just inside): the compiled sliding
    projection from the previous face (and `follow_closest`, which stays on a face whose
    interior holds the foot) gives the brute-force closest point over all faces."""
    rng = np.random.default_rng(7)
    s = boundary_surface(box_basis(name))
    nb = face_neighbours(s)
    lo, hi = np.zeros(3), np.array([2.0, 1.0, 0.5])
    p = np.array([1.0, 0.5, 0.6])
    face = closest_point(s, p).face
    out = np.empty(9)
    checked = corners = 0
    for _ in range(600):
        trial = p + rng.normal(0.0, 0.06, 3)
        outside = np.linalg.norm(np.maximum(np.maximum(lo - trial, trial - hi), 0.0))
        inside = np.min(np.minimum(trial - lo, hi - trial))
        if not (0.0 < outside < 0.3 or 0.0 < inside < 0.1):
            continue
        p = trial
        face = (follow_closest if follow else slide_closest)(s.nodes, s.kind, nb, face, p, out)
        d2, points = brute_force(s, p)
        assert np.isclose(out[8], outside if outside > 0 else -inside, rtol=1e-10, atol=1e-13)
        assert np.isclose(out[8] ** 2, d2, rtol=1e-10, atol=1e-14)
        assert any(np.allclose(out[2:5], x, atol=1e-9) for x in points)
        checked += 1
        corners += int(np.sum((p < lo) | (p > hi)) >= 2)
    assert checked > 300 and corners > 20


@pytest.mark.parametrize("name", ["hex20", "tet10"])
def test_foot_on_an_edge_between_coplanar_faces_is_kept_without_sliding(name):
    """A centre above a line of nodes of the flat top face (its foot on the edge shared by
    two faces, as at the paper's rigid layers) keeps the seed face with the brute-force
    foot and distance; a centre just past the seed face's edge, over its neighbour, still
    slides to the neighbour (the edge's clamped foot is not along the seed face's normal)."""
    s = boundary_surface(box_basis(name))
    nb = face_neighbours(s)
    out = np.empty(9)
    p = np.array([1.0, 0.5, 0.7])  # above the line x = 1 (element edges) of the top face z = 0.5
    seed = closest_point(s, p).face
    assert follow_closest(s.nodes, s.kind, nb, seed, p, out) == seed
    d2, points = brute_force(s, p)
    assert out[8] == pytest.approx(0.2, rel=1e-12) and np.isclose(out[8] ** 2, d2, rtol=1e-12)
    assert any(np.allclose(out[2:5], x, atol=1e-12) for x in points)
    x_seed = s.nodes[seed][:, 0]
    past = np.array([x_seed.max() + 0.05 if x_seed.max() < 1.5 else x_seed.min() - 0.05, 0.5, 0.7])
    face = follow_closest(s.nodes, s.kind, nb, seed, past, out)
    assert face != seed and np.isclose(out[8], 0.2, rtol=1e-12)
    assert np.allclose(out[2:5], [past[0], past[1], 0.5], atol=1e-12)


def test_curved_face_projection():
    """On a curved quad9 face (nodes on a cylinder of radius 1) the projection is the
    minimum over a dense grid of the face's reference points, and p - x is normal to it."""
    ref = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1], [0, -1], [1, 0], [0, 1], [-1, 0], [0, 0]], float)
    angle, height = 0.4 * ref[:, 0], 0.5 * ref[:, 1]
    X = np.stack([np.cos(angle), np.sin(angle), height], axis=1)
    from granplate.solid.surface import face_normal, face_shape_functions

    g = np.linspace(-1, 1, 801)
    N, dN = np.empty(9), np.empty((9, 2))
    grid = []
    for a in g[::4]:
        for b in g[::4]:
            face_shape_functions(QUAD9, a, b, N, dN)
            grid.append(N @ X)
    grid = np.array(grid)
    out, n = np.empty(9), np.empty(3)
    for p in ([1.5, 0.1, 0.2], [0.4, -0.1, -0.1], [1.2, 0.8, 0.1], [1.3, -0.6, 0.9]):
        p = np.array(p)
        d2 = face_closest(X, QUAD9, p, out)
        assert np.sqrt(d2) <= np.min(np.linalg.norm(grid - p, axis=1)) + 1e-12
        assert np.sqrt(d2) >= np.min(np.linalg.norm(grid - p, axis=1)) - 5e-3
        if np.all(np.abs(out[:2]) < 1 - 1e-9):  # an interior foot: p - x along the normal
            face_normal(X, QUAD9, out[0], out[1], n)
            r = p - out[2:5]
            assert np.allclose(np.cross(r, n), 0.0, atol=1e-10)


def test_named_groups_and_bad_input():
    """A named facet group gives just its faces; an unknown group is a ScenarioError naming it."""
    basis = cube_basis("hex20")
    mesh = basis.mesh.with_boundaries({"top": lambda x: np.isclose(x[2], 1.0)})
    top = boundary_surface(Basis(mesh, basis.elem), groups=("top",))
    assert top.n_faces == 4 and np.allclose(top.nodes[..., 2], 1.0)
    with pytest.raises(ScenarioError, match="bottom"):
        boundary_surface(Basis(mesh, basis.elem), groups=("bottom",))
    with pytest.raises(ScenarioError, match="point"):
        closest_point(top, [0.0, np.nan, 1.0])


@pytest.mark.parametrize("kind", [QUAD8, QUAD9, TRI6])
def test_shape_functions_are_nodal_and_their_derivatives_match_differences(kind):
    """N_k(node j) = delta_kj, and dN, d2N equal central differences of N and dN."""
    from granplate.solid.surface import (
        NODES_PER_FACE,
        _QUAD_NODES,
        _TRI_NODES,
        face_shape_functions,
        face_shape_hessians,
    )

    n = NODES_PER_FACE[kind]
    ref = (_TRI_NODES if kind == TRI6 else _QUAD_NODES)[:n]
    N, dN, d2N = np.empty(n), np.empty((n, 2)), np.empty((n, 3))
    for j, (a, b) in enumerate(ref):
        face_shape_functions(kind, a, b, N, dN)
        assert np.allclose(N, np.eye(n)[j], atol=1e-14)
    a, b, h = 0.23, 0.31, 1e-5

    def at(x, y):
        Nx, dNx = np.empty(n), np.empty((n, 2))
        face_shape_functions(kind, x, y, Nx, dNx)
        return Nx, dNx

    face_shape_functions(kind, a, b, N, dN)
    face_shape_hessians(kind, a, b, d2N)
    assert np.allclose(dN[:, 0], (at(a + h, b)[0] - at(a - h, b)[0]) / (2 * h), atol=1e-8)
    assert np.allclose(dN[:, 1], (at(a, b + h)[0] - at(a, b - h)[0]) / (2 * h), atol=1e-8)
    assert np.allclose(d2N[:, 0], (at(a + h, b)[1][:, 0] - at(a - h, b)[1][:, 0]) / (2 * h), atol=1e-7)
    assert np.allclose(d2N[:, 1], (at(a, b + h)[1][:, 0] - at(a, b - h)[1][:, 0]) / (2 * h), atol=1e-7)
    assert np.allclose(d2N[:, 2], (at(a, b + h)[1][:, 1] - at(a, b - h)[1][:, 1]) / (2 * h), atol=1e-7)


def test_weights_are_the_element_space_at_the_point(cube):
    """For a random displacement of the element space (any dof vector), sum_k w_k u_k equals
    the field scikit-fem evaluates at the point (basis.probes): the work F . u is exact."""
    _, basis, s = cube
    rng = np.random.default_rng(11)
    x = rng.normal(size=basis.N)
    for _ in range(6):
        cp = closest_point(s, rng.uniform(-0.3, 1.3, 3))
        dofs, w = patch_weights(s, cp.face, cp.xi)
        inward = cp.point - 1e-12 * (cp.point - 0.5)  # inside the element for the point search
        probe = basis.probes(inward[:, None])  # (3, N): the components at the point
        assert np.allclose(w @ x[dofs], probe @ x, atol=1e-9)

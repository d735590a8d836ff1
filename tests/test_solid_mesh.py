"""The solid's meshes: a box's named faces, a Gmsh file's physical groups, and each bad
input refused with one message naming the field."""

from __future__ import annotations

import numpy as np
import pytest

from granplate.errors import ScenarioError
from granplate.solid.mesh import BOX_FACES, box_mesh, corner_jacobians, face_facets, read_mesh

meshio = pytest.importorskip("meshio")

#: Two unit cubes side by side along x (VTK order), and the left face x = 0 as a quad.
POINTS = np.array([[x, y, z] for z in (0.0, 1.0) for y in (0.0, 1.0) for x in (0.0, 1.0, 2.0)])


def _node(x, y, z):
    return int(np.flatnonzero((POINTS == [x, y, z]).all(axis=1))[0])


def _hex(x0):
    return [
        _node(x0 + dx, y, z)
        for (dx, y, z) in [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
    ]


def write_msh(path, hexes=None, quads=None, groups=None, cell_type="hexahedron"):
    hexes = [_hex(0), _hex(1)] if hexes is None else hexes
    quads = [[_node(0, 0, 0), _node(0, 1, 0), _node(0, 1, 1), _node(0, 0, 1)]] if quads is None else quads
    groups = {"left": [1, 2], "body": [2, 3]} if groups is None else groups
    cells = [(cell_type, np.array(hexes)), ("quad", np.array(quads))]
    phys = [np.full(len(hexes), 2), np.full(len(quads), 1)]
    m = meshio.Mesh(
        POINTS,
        cells,
        cell_data={"gmsh:physical": phys, "gmsh:geometrical": phys},
        field_data={k: np.array(v) for k, v in groups.items()},
    )
    meshio.write(str(path), m, file_format="gmsh22", binary=False)
    return path


def test_box_faces_cover_the_boundary():
    """A box's six named faces hold every boundary facet once, each face nx ny (etc.) facets."""
    mesh = box_mesh([0.3, 0.2, 0.1], [3, 2, 1])
    sizes = {name: len(face_facets(mesh, name, "f")) for name in BOX_FACES}
    assert sizes == {"xmin": 2, "xmax": 2, "ymin": 3, "ymax": 3, "zmin": 6, "zmax": 6}
    assert sum(sizes.values()) == len(mesh.boundary_facets())


def test_box_volume_and_positive_jacobians():
    """Hexahedra and tetrahedra of a box fill its volume with positive Jacobians."""
    for tet in (False, True):
        mesh = box_mesh([0.3, 0.2, 0.1], [3, 2, 1], origin=[1.0, 2.0, 3.0], tetrahedra=tet)
        assert np.allclose(mesh.p.min(axis=1), [1.0, 2.0, 3.0]) and np.allclose(mesh.p.max(axis=1), [1.3, 2.2, 3.1])
    cells = np.array([_hex(0)])
    assert np.allclose(corner_jacobians(POINTS, cells), 1.0)


def test_gmsh_file_with_named_surface(tmp_path):
    """A Gmsh file's hexahedra and its physical surface group 'left' (one quad at x = 0)."""
    mesh = read_mesh(write_msh(tmp_path / "box.msh"))
    assert mesh.t.shape == (8, 2)
    left = face_facets(mesh, "left", "plate.clamped")
    assert len(left) == 1 and np.allclose(mesh.p[0, mesh.facets[:, left[0]]], 0.0)


def test_bad_files_say_why(tmp_path):
    """Unreadable, unsupported cells, inverted cells and a missing face name: one message each."""
    bad = tmp_path / "bad.msh"
    bad.write_text("not a mesh")
    with pytest.raises(ScenarioError, match="cannot be read") as e:
        read_mesh(bad)
    assert e.value.field == "plate.mesh"
    with pytest.raises(ScenarioError, match="no such file"):
        read_mesh(tmp_path / "absent.msh")
    wedge = tmp_path / "wedge.msh"
    meshio.write(
        str(wedge), meshio.Mesh(POINTS, [("wedge", np.array([[0, 1, 3, 6, 7, 9]]))]), file_format="gmsh22", binary=False
    )
    with pytest.raises(ScenarioError, match="no supported volume cells"):
        read_mesh(wedge)
    flipped = _hex(0)
    flipped[1], flipped[3] = flipped[3], flipped[1]  # mirrored: negative Jacobian
    with pytest.raises(ScenarioError, match="inverted"):
        read_mesh(write_msh(tmp_path / "inv.msh", hexes=[flipped, _hex(1)]))
    flat = _hex(0)
    flat[4:] = flat[:4]  # a cell of no height
    with pytest.raises(ScenarioError, match="degenerate"):
        read_mesh(write_msh(tmp_path / "flat.msh", hexes=[flat, _hex(1)]))
    mesh = read_mesh(write_msh(tmp_path / "box.msh"))
    with pytest.raises(ScenarioError, match="no such face.*'left'") as e:
        face_facets(mesh, "top", "plate.clamped")
    assert e.value.field == "plate.clamped"


def test_gmsh_file_with_an_unused_point_keeps_its_named_face(tmp_path):
    """A geometry point no cell uses is dropped and the nodes renumbered: the group 'left'
    is still the one quad at x = 0."""
    pts = np.vstack([[9.0, 9.0, 9.0], POINTS])  # the unused point first: every index moves
    hexes = np.array([_hex(0), _hex(1)]) + 1
    quads = np.array([[_node(0, 0, 0), _node(0, 1, 0), _node(0, 1, 1), _node(0, 0, 1)]]) + 1
    m = meshio.Mesh(
        pts,
        [("hexahedron", hexes), ("quad", quads)],
        cell_data={"gmsh:physical": [np.full(2, 2), np.full(1, 1)], "gmsh:geometrical": [np.full(2, 2), np.full(1, 1)]},
        field_data={"left": np.array([1, 2]), "body": np.array([2, 3])},
    )
    meshio.write(str(tmp_path / "extra.msh"), m, file_format="gmsh22", binary=False)
    mesh = read_mesh(tmp_path / "extra.msh")
    assert mesh.p.shape == (3, 12)
    left = face_facets(mesh, "left", "plate.clamped")
    assert len(left) == 1 and np.allclose(mesh.p[0, mesh.facets[:, left[0]]], 0.0)


@pytest.mark.parametrize("tetrahedra", [False, True])
def test_outline_of_a_box_is_its_twelve_edges(tetrahedra):
    """A box's outline (hexahedra or tetrahedra, whose faces' diagonals lie flat) runs along
    its 12 edges only: total length 4 (Lx + Ly + Lz), every end point on two of its faces;
    the face xmin's outline is its perimeter 2 (Ly + Lz)."""
    from granplate.solid.mesh import boundary_polygons, outline_edges

    size = np.array([0.3, 0.2, 0.1])
    mesh = box_mesh(size, [3, 2, 1], tetrahedra=tetrahedra)
    edges = outline_edges(mesh)
    length = lambda e: np.linalg.norm(e[:, 1] - e[:, 0], axis=1).sum()  # noqa: E731
    assert length(edges) == pytest.approx(4.0 * size.sum(), rel=1e-12)
    ends = edges.reshape(-1, 3)
    assert np.all((np.isclose(ends, 0.0, atol=1e-15) | np.isclose(ends, size)).sum(axis=1) >= 2)
    assert length(outline_edges(mesh, face_facets(mesh, "xmin", "f"))) == pytest.approx(2 * (0.2 + 0.1), rel=1e-12)
    polygons = boundary_polygons(mesh)  # in order around each facet: their areas add up to the surface
    area = sum(0.5 * np.linalg.norm(sum(np.cross(p[k], p[(k + 1) % len(p)]) for k in range(len(p)))) for p in polygons)
    assert area == pytest.approx(2 * (0.3 * 0.2 + 0.3 * 0.1 + 0.2 * 0.1), rel=1e-12)

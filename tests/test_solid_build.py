"""build_solid: the arrays kept in the run store come back equal; the residual is over the
top face's z dofs; a body too large is refused with its numbers; a 3D scenario's
[plate] is a solid, checked field by field, valid, and still refused to run."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

from granplate.errors import ScenarioError
from granplate.setup import io as scenario_io
from granplate.setup.scenario import SOLID_MAX_FREQUENCY, Solid
from granplate.setup.validate import validate
from granplate.setup.geometry import resolve
from granplate.solid.build import build_solid

SMALL = Solid(size=(0.03, 0.02, 0.004), elements=(3, 2, 1), clamped=("xmin",), max_frequency=1e5)


def test_build_is_stored_and_read_back(tmp_path, monkeypatch):
    """A second build reads the run store's arrays: the same modes and residual bitwise."""
    monkeypatch.setenv("GRANPLATE_CACHE", str(tmp_path))
    a = build_solid(SMALL)
    b = build_solid(SMALL)
    assert a.arrays_key and a.arrays_key == b.arrays_key
    assert np.array_equal(a.omega, b.omega) and np.array_equal(a.resid, b.resid)
    assert any((tmp_path / "solid").iterdir())
    z = a.nodes[a.dofs[a.surface_dofs] // 3, 2]
    assert np.all(a.dofs[a.surface_dofs] % 3 == 2) and np.allclose(z, 0.004)
    assert a.resid.shape == (len(a.surface_dofs),) * 2 and np.allclose(a.resid, a.resid.T)
    assert set(a.faces) == {"xmin", "xmax", "ymin", "ymax", "zmin", "zmax"}


def test_residual_on_demand_equals_the_stored_one():
    """residual_block over a few of the top face's dofs equals those entries of the face's R."""
    m = build_solid(SMALL, cache=False)
    pick = np.array([0, 3, 5])
    assert np.allclose(
        m.residual_block(m.surface_dofs[pick]),
        m.resid[np.ix_(pick, pick)],
        rtol=1e-10,
        atol=1e-10 * np.abs(m.resid).max(),
    )


def test_too_big_is_refused_with_numbers():
    """A body over the memory allowed: one ScenarioError with dofs, GB and what to change."""
    with pytest.raises(ScenarioError, match=r"dofs.*GB.*fewer elements.*max_frequency") as e:
        build_solid(SMALL, cache=False, memory=1e3)
    assert e.value.field == "plate.elements"


BASE = {
    "name": "solid",
    "dimension": 3,
    "granules": [{"x": 0.01, "y": 0.01, "z": 0.02, "radius": 0.002, "material": "steel"}],
    "plate": {"size": [0.03, 0.02, 0.004], "elements": [3, 2, 1], "clamped": ["xmin"]},
}


def refusal(d: dict) -> ScenarioError | None:
    """The ScenarioError validating the scenario of dict d raises, None when it is valid."""
    try:
        validate(scenario_io.from_dict(d))
    except ScenarioError as e:
        return e
    return None


def scenario(**plate):
    d = copy.deepcopy(BASE)
    d["plate"].update(plate)
    for k in [k for k, v in d["plate"].items() if v is None]:
        del d["plate"][k]
    return scenario_io.from_dict(d)


def test_3d_plate_is_a_solid_with_defaults():
    """The [plate] of a 3D scenario reads as a Solid: hex20, origin 0 once resolved, the measured default cut-off (150 kHz)."""
    s = scenario()
    assert isinstance(s.plate, Solid)
    assert s.plate.element == "hex20" and s.plate.origin is None  # placed by resolve
    assert resolve(s).plate.origin == (0.0, 0.0, 0.0)  # no layout: at the origin
    assert s.plate.max_frequency == SOLID_MAX_FREQUENCY == 1.5e5


def test_valid_solid_validates_and_builds_its_model_with_the_verlet_scheme():
    """A scenario file with a solid and no [solver] scheme reads with scheme "verlet" (the
    scheme that couples a solid), validates and builds its model with the body's arrays; the
    same scenario told to use "paper" is refused naming solver.scheme."""
    import dataclasses

    from granplate.model import build_model

    s = scenario()
    assert s.solver.scheme == "verlet"
    validate(s)
    m = build_model(s)
    assert m.body is not None and m.body.phi.shape == (len(m.solid.dofs), m.solid.n_modes)
    bad = dataclasses.replace(s, solver=dataclasses.replace(s.solver, scheme="paper"))
    with pytest.raises(ScenarioError, match="verlet") as e:
        validate(bad)
    assert e.value.field == "solver.scheme"


@pytest.mark.parametrize(
    "change,field,words",
    [
        ({"element": "hex8"}, "plate.element", "'hex20', 'hex27', 'tet10'"),
        ({"clamped": ["top"]}, "plate.clamped", "must be one of 'xmin'"),
        ({"rollers": ["xmin"]}, "plate.rollers", "both clamped and on rollers"),
        ({"elements": [3, 0, 1]}, "plate.elements[1]", "integer in [1, 1000]"),
        ({"size": [0.03, -1.0, 0.004]}, "plate.size[1]", "> 0"),
        ({"size": None}, "plate.size", "needs size"),
        ({"mesh": "a.msh"}, "plate.mesh", "excludes plate.size"),
        ({"max_frequency": 0.1}, "plate.max_frequency", "Hz"),
        ({"material": "stel"}, "plate.material", "unknown material"),
    ],
)
def test_bad_solid_fields_name_the_field(change, field, words):
    """Each bad solid field is one ScenarioError naming it and its allowed range."""
    with pytest.raises(ScenarioError) as e:
        validate(scenario(**change))
    assert e.value.field == field and words in str(e.value), str(e.value)


def test_build_from_a_gmsh_file(tmp_path):
    """A Gmsh file's solid clamped on its group 'left': its faces by name, its modes, and a
    clear refusal of a face the file does not name and of an element of the other cell type."""
    from test_solid_mesh import write_msh

    path = str(write_msh(tmp_path / "bar.msh"))
    m = build_solid(Solid(mesh=path, clamped=("left",), max_frequency=2e3), surface=None, cache=False)
    assert "left" in m.faces and m.n_modes >= 1 and not m.free
    assert np.all(m.nodes[m.faces["left"], 0] == 0.0)
    with pytest.raises(ScenarioError, match="must be one of 'left'") as e:
        build_solid(Solid(mesh=path, clamped=("xmin",)), surface=None, cache=False)
    assert e.value.field == "plate.clamped"
    with pytest.raises(ScenarioError, match="does not fit the mesh file's cells"):
        build_solid(Solid(mesh=path, element="tet10"), surface=None, cache=False)


def test_free_body_build_keeps_rigid_modes_and_a_residual():
    """A box held nowhere: six zero modes first, and the inertia-relief residual over its
    top face equals the on-demand one."""
    m = build_solid(Solid(size=(0.02, 0.01, 0.005), elements=(2, 2, 1), max_frequency=4e5), cache=False)
    assert m.free and np.all(m.omega[:6] == 0.0) and m.omega[6] > 0.0
    pick = np.array([0, 2, 7])
    assert np.allclose(
        m.residual_block(m.surface_dofs[pick]),
        m.resid[np.ix_(pick, pick)],
        rtol=1e-9,
        atol=1e-9 * np.abs(m.resid).max(),
    )


def test_residual_beside_the_eigensolver_leaves_blas_threads_and_rigid_modes_as_they_were():
    """The residual's flexibility runs in a second thread beside the eigensolver: after the
    build every BLAS library has its former thread count, and the rigid modes it used
    (rigid_modes, known before the eigensolver) are the modes' first six, M-orthonormal."""
    threadpoolctl = pytest.importorskip("threadpoolctl")
    from granplate.solid.boundary import reduced
    from granplate.solid.fe import mass_matrix
    from granplate.solid.modes import rigid_modes

    counts = lambda: [p["num_threads"] for p in threadpoolctl.threadpool_info() if p["user_api"] == "blas"]
    before = counts()
    m = build_solid(Solid(size=(0.02, 0.01, 0.005), elements=(2, 2, 1), max_frequency=4e5), cache=False)
    assert counts() == before
    M = reduced(mass_matrix(m.basis, m.material.rho), m.dofs)
    R = rigid_modes(m.nodes, M)
    assert np.array_equal(R, m.Phi[:, :6]) and np.allclose(R.T @ (M @ R), np.eye(6), atol=1e-12)


def test_box_signed_distance_is_the_euclidean_distance_to_the_box():
    """Outside: the distance to the nearest face, edge or corner (Pythagoras); inside: minus
    the distance to the nearest face; zero on the surface."""
    from granplate.setup.solid_checks import box_signed_distance

    lo, hi = (0.0, 0.0, 0.0), (3.0, 2.0, 1.0)
    assert box_signed_distance(lo, hi, (1.0, 1.0, 1.5)) == 0.5  # above the top face
    assert box_signed_distance(lo, hi, (4.0, 1.0, 2.0)) == math.sqrt(2.0)  # off an edge
    assert box_signed_distance(lo, hi, (-1.0, -2.0, 3.0)) == 3.0  # off a corner: sqrt(1+4+4)
    assert box_signed_distance(lo, hi, (1.0, 1.0, 0.75)) == -0.25  # inside, nearest the top
    assert box_signed_distance(lo, hi, (3.0, 0.5, 0.5)) == 0.0


@pytest.mark.parametrize("z,ok", [(0.006, True), (0.006 * (1 - 1e-6), False), (0.0039, False), (0.003, False)])
def test_a_granule_may_touch_the_solid_but_not_cross_it(z, ok):
    """A sphere of radius 2 mm above the top face (z = 4 mm): touching (z = 6 mm) is valid; a
    penetration by more than 1e-9 R names the granule, the overlap and what to move; a
    centre inside the body is always refused."""
    d = copy.deepcopy(BASE)
    d["granules"][0]["z"] = z
    e = refusal(d)
    assert (e is None) == ok
    if ok:
        return
    msg = str(e)
    assert e.field == "granules[0]" and "plate.origin" in msg and "\n" not in msg, msg
    if z > 0.004:
        assert "penetrates the elastic solid" in msg and f"by {0.006 - z:.6g} m" in msg, msg
    else:
        assert "centre inside the elastic solid" in msg and f"{0.004 - z:.6g} m below its surface" in msg, msg


def test_a_granule_beside_the_box_is_clear_of_it():
    """A sphere off the box's edge x = 30 mm, z = 4 mm by 1.5 mm along both: closer than its
    radius to both face planes, but sqrt(2) 1.5 mm = 2.12 mm from the edge, its nearest
    point: radius 2 mm is clear, radius 2.2 mm penetrates by 2.2 - 2.12 mm."""
    d = copy.deepcopy(BASE)
    d["granules"][0].update(x=0.0315, z=0.0055, radius=0.002)
    validate(scenario_io.from_dict(d))
    d["granules"][0].update(radius=0.0022)
    with pytest.raises(
        ScenarioError, match=f"penetrates the elastic solid.* by {0.0022 - math.sqrt(2) * 0.0015:.6g} m"
    ):
        validate(scenario_io.from_dict(d))


@pytest.mark.parametrize(
    "wall,field,ok",
    [
        ({"normal": [0, 0, -1], "offset": -0.004}, "walls[0]", False),  # along the face the granule meets
        ({"normal": [0, 0, -1], "offset": -0.002}, "walls[0]", False),  # through the body
        ({"normal": [0, 0, -2], "offset": -0.004}, "walls[0]", False),  # any normal's length: the unit normal's offset
        ({"normal": [0, -1, 0], "offset": 0.0}, None, True),  # along a side face the granule does not meet
        ({"normal": [0, 0, 1], "offset": 0.01}, None, True),  # above the granule, clear of the body
    ],
)
def test_a_wall_may_not_cross_the_solid_or_lie_on_the_face_a_granule_meets(wall, field, ok):
    """A rigid wall through the box, or along the face a granule touches at t = 0 (the
    granule then touches both at one point, and the wall would carry the solid's load), is
    refused naming the wall; a wall along a face no granule meets is valid (the paper's
    bottom wall along the clamped edge of its 3D twin)."""
    d = copy.deepcopy(BASE)
    d["granules"][0]["z"] = 0.006  # touching the top face z = 4 mm
    d["walls"] = [wall]
    e = refusal(d)
    assert (e is None) == ok
    assert ok or (e.field == field and "take the load the solid should" in str(e))


def test_a_layouts_wall_on_the_plates_face_is_refused_naming_layout_walls():
    """An fcc packing's default xmax wall lies on the face of the plate placed against it:
    refused naming layout.walls and the list without it; walls = [] runs."""
    d = {
        "name": "w",
        "dimension": 3,
        "layout": {"kind": "fcc", "cells": [1, 1, 1], "radius": 0.0025},
        "plate": {"size": [0.004, 0.02, 0.02], "elements": [1, 2, 2], "clamped": ["ymin", "ymax"]},
    }
    with pytest.raises(ScenarioError) as e:
        validate(scenario_io.from_dict(d))
    assert e.value.field == "layout.walls" and e.value.value == "xmax" and "'zmax']" in str(e.value)
    d["layout"]["walls"] = []
    validate(scenario_io.from_dict(d))


def test_a_study_of_a_solid_gives_designs_that_build(tmp_path):
    """A study whose base has a solid: every design's scenario reads back with the verlet
    scheme, validates and builds its model (the sweep runs them as any other)."""
    from granplate.model import build_model
    from granplate.study.spec import parse_study

    (tmp_path / "base.toml").write_text(scenario_io.dumps(scenario()))
    study = parse_study({"base": "base.toml", "parameters": {"granules[0].z": [0.0061, 0.007]}}, tmp_path)
    for i in range(2):
        s = study.scenario(i)
        assert s.solver.scheme == "verlet"
        validate(s)
        assert build_model(s).body is not None


def test_a_solid_alone_and_the_other_dimension_s_plate():
    """A 3D scenario of a solid alone validates (nothing to touch it); a solid in 2D and a
    plane-stress plate in 3D are refused naming the plate and the dimension."""
    import dataclasses

    from granplate.setup.scenario import Plate, Scenario

    alone = dataclasses.replace(scenario(), granules=())
    validate(alone)
    validate(dataclasses.replace(alone, plate=Solid(mesh="any.msh")))  # its file is read when drawn or built
    with pytest.raises(ScenarioError, match="elastic solid.*is 3D.*dimension = 3") as e:
        validate(Scenario(plate=SMALL))
    assert e.value.field == "plate"
    with pytest.raises(ScenarioError, match="in 3D the \\[plate\\] is an elastic solid") as e:
        validate(dataclasses.replace(alone, plate=Plate(x0=0.1)))
    assert e.value.field == "plate"


def test_residual_off_builds_no_residual_and_bad_values_are_refused():
    """plate.residual = false: the body's loop arrays hold no residual compliance (the modes
    alone); a non-boolean and a non-positive stress_radius are refused naming the field."""
    from granplate.model import build_model

    m = build_model(scenario(residual=False))
    assert m.body.resid.shape == (0, 0) and np.all(m.body.node_resid < 0)
    assert build_model(scenario()).body.resid.shape[0] > 0
    for change, field in (({"residual": 1}, "plate.residual"), ({"stress_radius": 0.0}, "plate.stress_radius")):
        with pytest.raises(ScenarioError) as e:
            validate(scenario(**change))
        assert e.value.field == field


def test_rigid_patch_moves_rigidly_in_every_mode_and_under_a_load():
    """A rigid patch (plate.rigid_patches) ties its surface nodes: in every kept mode their
    motion is a rigid motion to within 1e-3 of its size (the tie's penalty, solid.tie.PENALTY
    = 1e4); too small a patch is refused naming it; a granule on it meets a rigid body (E*
    of the granule alone: a larger Hertz coefficient, and no damping)."""
    import dataclasses

    from granplate.model import build_model
    from granplate.physics.contact import COEF_A, COEF_C
    from granplate.setup.scenario import RigidPatch
    from granplate.solid.fe import vector_basis
    from granplate.solid.surface import boundary_surface
    from granplate.solid.tie import facing_nodes, patch_nodes, rigid_basis

    patch = RigidPatch(centre=(0.01, 0.01, 0.004), radius=0.006)
    s = scenario(
        rigid_patches=[{"centre": list(patch.centre), "radius": patch.radius}],
        max_frequency=2e5,
        elements=[4, 4, 1],
        size=[0.02, 0.02, 0.004],
    )
    s = dataclasses.replace(s, granules=(dataclasses.replace(s.granules[0], x=0.01, y=0.01, z=0.006),))
    validate(s)
    m = build_solid(s.plate, cache=False)
    surface = boundary_surface(vector_basis(m.mesh, m.element))
    nodes = patch_nodes(*facing_nodes(surface, patch.centre), patch.centre, patch.radius, 0)  # face zmax's only
    assert len(nodes) >= 5
    full = (3 * nodes[:, None] + np.arange(3)).ravel()
    rows = np.searchsorted(m.dofs, full)
    Q = rigid_basis(m.nodes[nodes])
    for k in range(m.n_modes):
        u = m.Phi[rows, k]
        assert np.linalg.norm(u - Q @ (Q.T @ u)) <= 1e-3 * np.linalg.norm(u) + 1e-300
    body = build_model(s)
    plain = build_model(dataclasses.replace(s, plate=dataclasses.replace(s.plate, rigid_patches=())))
    assert body.body.coef[0, COEF_A] > plain.body.coef[0, COEF_A]  # a rigid partner: the granule's E* alone
    assert body.body.coef[0, COEF_C] == 0.0 and plain.body.coef[0, COEF_C] > 0.0
    tiny = scenario(rigid_patches=[{"centre": [0.01, 0.01, 0.004], "radius": 1e-4}])
    with pytest.raises(ScenarioError) as e:
        build_solid(tiny.plate, cache=False)
    assert e.value.field == "plate.rigid_patches[0]"

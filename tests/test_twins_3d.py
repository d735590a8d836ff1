"""The paper's presets in 3D (setup.presets.twin_3d): planar packings in space, the solid
placed against them, rigid layers as translation-only strips, the line load in space, and
the thin-limit agreement with the 2D presets."""

import math

import numpy as np
import pytest

import granplate as gp
from granplate.model.arrays import build_model
from granplate.setup.geometry import resolve
from granplate.setup.presets import preset
from granplate.setup.validate import validated


def test_planar_packing_in_space_keeps_the_plane_geometry():
    """A 3D twin's granules are the 2D preset's at z = 0, its walls the same lines as planes."""
    a, b = resolve(preset("ptfe-r05")), resolve(validated(preset("3d-ptfe-r05")))
    assert [(g.x, g.y, g.radius, g.label) for g in a.granules] == [(g.x, g.y, g.radius, g.label) for g in b.granules]
    assert all(g.z == 0.0 and g.omega == (0.0, 0.0, 0.0) for g in b.granules)
    assert [(tuple(w.normal) + (0.0,), w.offset) for w in a.walls] == [(tuple(w.normal), w.offset) for w in b.walls]


def test_solid_against_the_packing_with_one_rigid_layer_per_touching_granule():
    """The slab's face xmin is the 2D plate's edge, centred on z = 0; one translation-only
    strip along z, w/2 = 1.25 mm, at each of A..E."""
    a, b = resolve(preset("ptfe-r05")), resolve(preset("3d-ptfe-r05"))
    assert b.plate.origin == pytest.approx((a.plate.x0, 0.0, -0.0005))
    ps = b.plate.rigid_patches
    assert len(ps) == 5 and not b.plate.rigid_layers
    assert sorted(p.centre[1] for p in ps) == pytest.approx([0.01, 0.03, 0.05, 0.07, 0.09])
    assert all(p.axis == (0.0, 0.0, 1.0) and not p.rotates and p.radius == pytest.approx(0.00125) for p in ps)
    assert resolve(b) == b  # idempotent


def test_rigid_layer_ties_the_face_it_lies_on_only():
    """A strip across a 1 mm slab holds the 7 hex20 nodes of face xmin within 1.25 mm of its
    line (3 at y_k, 2 on each side), none on the side faces zmin, zmax."""
    from granplate.solid.build import solid_mesh
    from granplate.solid.fe import vector_basis
    from granplate.solid.surface import boundary_surface
    from granplate.solid.tie import facing_nodes, patch_nodes

    sd = resolve(preset("3d-ptfe-r05")).plate
    surface = boundary_surface(vector_basis(solid_mesh(sd), sd.element))
    p = sd.rigid_patches[2]
    xyz, ids = facing_nodes(surface, p.centre)
    nodes = patch_nodes(xyz, ids, p.centre, p.radius, 2, p.axis)
    assert len(nodes) == 7
    assert np.allclose(xyz[np.isin(ids, nodes), 0], sd.origin[0])


def test_line_load_in_space_equals_the_plane_resultants():
    """The 3D model's per-granule shock forces and torques are the 2D closed forms."""
    a, b = build_model(resolve(preset("ptfe-r05"))), build_model(resolve(validated(preset("3d-ptfe-r05"))))
    assert np.allclose(b.granular.shock_force[:, 0], a.granular.shock_force)
    assert np.allclose(b.granular.shock_torque[:, 2], a.granular.shock_torque)
    assert not b.granular.shock_force[:, 1:].any() and not b.granular.shock_torque[:, :2].any()


def test_face_traction_totals_the_line_load():
    """The nodal forces of the bare plate's load on face xmin sum to q0 2L/pi (per unit q0)."""
    from granplate.solid.build import solid_mesh
    from granplate.solid.fe import vector_basis
    from granplate.solid.surface import boundary_surface
    from granplate.solid.traction import face_xmin_line_load

    s = resolve(preset("3d-bare-plate"))
    sd = s.plate
    surface = boundary_surface(vector_basis(solid_mesh(sd), sd.element))
    n_full = 3 * int(surface.dofs.max() // 3 + 1)
    f = face_xmin_line_load(surface, n_full, sd.origin[0], sd.size[2], s.load.y0, s.load.length, 1e-12)
    assert f[1::3].sum() == 0.0 and f[2::3].sum() == 0.0
    assert f[0::3].sum() == pytest.approx(2.0 * s.load.length / math.pi, rel=1e-6)


@pytest.mark.parametrize("name,t_end", [("bare-plate", 5e-5), ("ptfe-r05", 1e-3)])
def test_thin_limit_twin_matches_the_plane(name, t_end):
    """In the thin limit the 3D twin reproduces the 2D preset: E_shock within 1%, the
    plate's peak share within 2% (ptfe-r05's peak is at 0.76 ms)."""
    a = gp.summary(gp.simulate(preset(name), t_end=t_end, progress=False))
    b = gp.summary(gp.simulate(preset("3d-" + name), t_end=t_end, progress=False))
    assert b["e_shock"] == pytest.approx(a["e_shock"], rel=0.01)
    assert b["ep_max_fraction"] == pytest.approx(a["ep_max_fraction"], rel=0.02)
    assert abs(b["energy_residual_max"]) < 1e-4


def test_granule_on_a_rigid_patch_reports_the_rigid_layers_pressure():
    """A granule on a rigid patch meets a rigid body (E* of the granule alone), so its
    Hertz peak pressure at a given overlap is the 2D rigid layer's; elsewhere on the body
    it is E* of both materials (eq. P2 with the loop's own coefficients)."""
    from granplate.physics.contact import COEF_A
    from granplate.results.yielding import contact_yield
    from granplate.solver.driver import ContactPeaks
    from granplate.solver.state import PARTNER_PLATE

    plane = build_model(resolve(preset("steel-r1")))
    space = build_model(resolve(validated(preset("3d-steel-r1"))))
    on = np.flatnonzero(space.body_rigid)
    assert set(plane.plate_contacts) <= set(on)  # every rigid layer's granule (and those behind it)
    i, d = int(plane.plate_contacts[2]), 2e-6
    peaks = ContactPeaks(np.array([i]), np.array([PARTNER_PLATE]), np.array([d]), np.array([0.0]))
    (row2,), (row3,) = contact_yield(plane, peaks), contact_yield(space, peaks)
    assert row3[0] == row2[0] == "steel-plate"
    assert row3[1] == pytest.approx(row2[1], rel=1e-12) and row3[2] == pytest.approx(row2[2], rel=1e-12)
    # the loop's own Hertz coefficient is the rigid body's too
    assert space.body.coef[i, COEF_A] == pytest.approx(plane.granular.pc_coef[2, COEF_A], rel=1e-12)
    k = int(np.flatnonzero(~space.body_rigid)[0])
    free = ContactPeaks(np.array([k]), np.array([PARTNER_PLATE]), np.array([d]), np.array([0.0]))
    assert contact_yield(space, free)[0][1] < 0.75 * row2[1]  # E* of steel on steel: softer, lower p0

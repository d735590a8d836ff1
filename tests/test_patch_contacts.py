"""Plate contacts that form during the run on the plate's face (docs/model.md section
3.5): against Hertz's rigid-wall impact on a stiff plate, against themselves at a node
and between nodes, Coulomb's bound when sliding, the energy balance of eq. (11) (exactly
across a patch move), the truncated basis against the full one, the fixed detection's
error kept, and the record of when and where each contact formed; granules touching the
face between nodes at t = 0 (patch contacts from the start) against the same granule
reaching the face during the run."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from granplate.errors import SimulationError
from granplate.model.arrays import build_model
from granplate.physics.contact import COEF_A, contact_energy
from granplate.results.run import simulate
from granplate.setup.materials import LIBRARY, effective_modulus, sphere_mass
from granplate.setup.scenario import Wall
from granplate.solver import driver, state as S
from granplate.solver.interface import move_patches
from granplate.solver.plate_modal import plate_energy
from granplate.verification.face_contacts import (
    R,
    STIFF_THICKNESS,
    X0,
    bounce,
    drop_scenario,
    node_spacing,
)
from granplate.verification.granular import hertz_reference

STEEL = LIBRARY["steel"]
BETWEEN = 0.05 + 0.37 * node_spacing(40)


def test_stiff_plate_impact_is_hertz_on_a_rigid_wall():
    """A granule thrown from a gap at a very stiff, heavy plate, between two nodes,
    gets a patch contact, stays in touch for Hertz's t_c and rebounds elastically."""
    ds = simulate(drop_scenario(BETWEEN, thickness=STIFF_THICKNESS, t_end=6.4e-4, out=2.5e-7), progress=False)
    b = bounce(ds)
    ref = hertz_reference(sphere_mass(R, STEEL.rho), effective_modulus(STEEL, None), R, 1.0)
    assert list(ds.contact.values) == ["g"] and ds.contact_y.values[0] == pytest.approx(BETWEEN)
    assert b["t_c"] == pytest.approx(ref["t_c"], rel=0.02)
    assert b["f_max"] == pytest.approx(ref["force_max"], rel=0.02)
    assert 0.99 < b["e"] <= 1.0
    assert b["residual"] < 1e-5


def test_impact_between_nodes_rebounds_as_at_a_node():
    """On the paper's plate the rebound (the energy the plate keeps) hardly depends on
    where the nodes are: the patch spreads the force over 2.5 mm either way."""
    at_node = bounce(simulate(drop_scenario(0.05, t_end=1e-3), progress=False))
    between = bounce(simulate(drop_scenario(BETWEEN, t_end=1e-3), progress=False))
    assert 0.8 < at_node["e"] < 0.99  # the plate keeps a share
    assert between["e"] == pytest.approx(at_node["e"], rel=0.02)
    assert between["t_c"] == pytest.approx(at_node["t_c"], rel=0.03)
    assert max(at_node["residual"], between["residual"]) < 1e-5


def test_sliding_granule_carries_its_patch_and_obeys_coulomb():
    """An oblique impact with friction: the granule slides past a face node while in
    touch; the tangential impulse stays within mu times the normal one, friction
    dissipates, and eq. (11) balances."""
    mu = 0.3
    ds = simulate(drop_scenario(0.05, vx=1.0, vy=4.0, mu=mu, t_end=1e-3, out=5e-7), progress=False)
    b = bounce(ds)
    assert b["travel"] > node_spacing(40)
    assert 0.1 * mu * b["j_n"] < abs(b["j_t"]) <= mu * b["j_n"] * 1.001
    assert ds.D_friction.values[-1] > 1e-3 * ds.E_granular.values[0]
    assert b["residual"] < 1e-5


def test_granule_leaves_and_comes_back_on_the_same_contact():
    """A granule between a wall and the plate hits the plate, flies back to the wall and
    hits the plate again: one patch contact, two separate touches, energy balanced."""
    s = drop_scenario(0.05, vx=2.0, t_end=2.8e-3)
    s = s.__class__(**{**s.__dict__, "walls": (Wall(normal=(-1.0, 0.0), offset=-(X0 - 2 * R - 1.6e-3)),)})
    ds = simulate(s, progress=False)
    fn = ds.contact_normal_force.values[:, 0]
    touching = fn > 0
    starts = np.flatnonzero(touching[1:] & ~touching[:-1])
    assert list(ds.contact.values) == ["g"]
    assert len(starts) >= 2  # two impacts on the plate
    assert abs(ds.energy_residual.values).max() < 1e-5


def test_moving_a_patch_changes_no_energy_term():
    """Move a loaded patch contact along a deformed face: its rows change, the stored
    contact energy and the plate's energy stay the same to round-off (the overlap is
    kept continuous), so eq. (11) is unaffected by the move."""
    model = build_model(drop_scenario(0.05, gap=6e-4))
    arr = driver.LoopArrays(model, np.array([0.0, 1e-6]), 0)
    lists = driver.ContactLists(model)
    lists.g = lists.g._replace(pc_x=lists.g.pc_x.copy())
    st, g, p, cfg = arr.st, lists.g, arr.p, model.config
    st.y[:] = model.initial_state
    arr.w.plate_free[:] = 1
    rng = np.random.default_rng(11)
    st.q[:] = rng.normal(size=st.q.shape) * 1e-9 / np.sqrt(p.omega2 / p.omega2[0])  # a deformed plate
    st.qd[:] = rng.normal(size=st.q.shape) * 1e-6
    assert driver.add_patch_contacts(model, lists, arr) == 1
    st, g, p, w = arr.st, lists.g, arr.p, arr.w
    st.y[0, 0] = X0 + st.u[0] - R + 2e-6  # 2 um into the face
    a = g.pc_coef[0, COEF_A]

    def energies():
        delta = st.y[0, 0] + R - (g.pc_x[0] + st.u[0])
        return contact_energy(delta, a), plate_energy(st.q, st.qd, st.force, p.omega2, p.resid)

    e_contact, e_plate = energies()
    rows = p.phi_d.copy()
    st.y[0, 1] += 0.37 * node_spacing(40)  # the granule slid
    assert move_patches(st, g, p, cfg, w)
    assert not np.array_equal(rows, p.phi_d) and g.pc_x[0] != X0
    e2_contact, e2_plate = energies()
    assert e_contact > 0 and e2_contact == pytest.approx(e_contact, rel=1e-9)
    assert e2_plate == e_plate
    assert not w.g_ok.any()  # the per-level matrices are stale
    st.y[0, 0] -= 1e-4  # the contact opens: the shift is released
    move_patches(st, g, p, cfg, w)
    assert g.pc_x[0] == X0


def test_fixed_detection_still_stops_at_the_plate():
    """contact.detection = "fixed": plate contacts are those at t = 0, and a granule that
    flies into the plate stops the run, naming it and what to change."""
    s = drop_scenario(0.05, gap=1e-3, t_end=1.5e-3)
    s = s.__class__(**{**s.__dict__, "contact": s.contact.__class__(pairs=(), detection="fixed")})
    with pytest.raises(
        SimulationError,
        match=r"granule 'g' \(at x = .* y = 0.05 m\) reached the plate's face "
        r"at t = 1.0\d*e-03 s.*detection = \"dynamic\"",
    ):
        simulate(s, progress=False)


def _truncated(s, cut: float = 4e5):
    """s with its plate on the truncated basis below `cut` [Hz]."""
    return dataclasses.replace(s, plate=dataclasses.replace(s.plate, modes="truncated", max_frequency=cut))


def test_truncated_basis_impact_between_nodes_agrees_with_all_modes():
    """A granule thrown between nodes at the paper's plate on the truncated basis (its
    patch contact corrected by w^T R_face w) bounces as on the full basis: contact time,
    restitution and the energy the plate keeps within 0.5%, eq. (11) balanced."""
    fast = dict(t_end=1e-3, out=1e-6)
    full = simulate(drop_scenario(BETWEEN, **fast), progress=False)
    trunc_s = _truncated(drop_scenario(BETWEEN, **fast))
    model = build_model(trunc_s)
    assert model.plate.truncated and model.plate.n_modes < model.plate.n_red and model.config.face_skin > 0
    trunc = simulate(trunc_s, model=model, progress=False)
    b_f, b_t = bounce(full), bounce(trunc)
    assert b_t["contacts"] == 1 and b_t["t_c"] == pytest.approx(b_f["t_c"], rel=5e-3)
    assert b_t["e"] == pytest.approx(b_f["e"], rel=5e-3)
    assert trunc.E_plate.values[-1] == pytest.approx(full.E_plate.values[-1], rel=5e-3)
    assert b_t["residual"] < 1e-5
    assert np.abs(trunc.plate_ux.values).max() > 0  # the fields take the patch's static part


def test_patch_sliding_on_a_truncated_basis_keeps_eq_11_and_agrees_with_all_modes():
    """A granule sliding along the face (no friction): its patch moves many times, each
    move's change of the static energy booked, so eq. (11) balances as on the full
    basis; the plate's energy and the rebound agree within 0.5%."""
    s = drop_scenario(0.05, vx=1.0, vy=4.0, t_end=1e-3, out=5e-7)
    full, trunc = simulate(s, progress=False), simulate(_truncated(s), progress=False)
    b_f, b_t = bounce(full), bounce(trunc)
    assert b_t["travel"] > node_spacing(40)
    assert b_t["residual"] < 2e-6 and b_f["residual"] < 2e-6
    assert b_t["e"] == pytest.approx(b_f["e"], rel=5e-3)
    assert trunc.E_plate.values[-1] == pytest.approx(full.E_plate.values[-1], rel=5e-3)


def test_moving_a_patch_on_a_truncated_basis_books_its_static_energy():
    """With a truncated basis a loaded patch that moves changes its static compliance
    w^T R_face w: the contact's overlap stays continuous, and the change of the plate's
    static energy 1/2 F^T R F is booked as energy put in, so eq. (11) is unchanged."""
    model = build_model(_truncated(drop_scenario(0.05, gap=6e-4)))
    arr = driver.LoopArrays(model, np.array([0.0, 1e-6]), 0)
    lists = driver.ContactLists(model)
    lists.g = lists.g._replace(pc_x=lists.g.pc_x.copy())
    st, cfg = arr.st, model.config
    st.y[:] = model.initial_state
    arr.w.plate_free[:] = 1
    assert driver.add_patch_contacts(model, lists, arr) == 1
    st, g, p, w = arr.st, lists.g, arr.p, arr.w
    assert p.resid.shape == (2, 2) and p.resid[0, 0] > 0
    st.force[:] = (-400.0, 30.0)  # [N] a loaded contact
    st.y[0, 0] = X0 + st.u[0] - R + 2e-6
    a = g.pc_coef[0, COEF_A]

    def energies():
        delta = st.y[0, 0] + R - (g.pc_x[0] + st.u[0])
        return contact_energy(delta, a), plate_energy(st.q, st.qd, st.force, p.omega2, p.resid), st.clock[S.E_ZERO]

    e_contact, e_plate, e_in = energies()
    resid = p.resid.copy()
    st.y[0, 1] += 0.37 * node_spacing(40)  # the granule slid off the node
    assert move_patches(st, g, p, cfg, w)
    e2_contact, e2_plate, e2_in = energies()
    assert not np.allclose(resid, p.resid, rtol=1e-3, atol=0)  # R moved with the patch
    assert e2_contact == pytest.approx(e_contact, rel=1e-9)
    assert e2_plate != e_plate and e2_plate - e_plate == pytest.approx(e2_in - e_in, rel=1e-12)


def test_patch_contacts_need_every_mode_or_the_static_correction():
    """A truncated basis gets patch contacts (face shapes and R_face in the loop's
    arrays); a dense basis cut to plate.n_modes has no static correction: a granule
    reaching the face stops the run, naming plate.n_modes and plate.modes."""
    model = build_model(_truncated(drop_scenario(0.05, ny=8), 2e5))
    assert model.config.face_skin > 0.0 and model.plate_arrays.resid_face.shape == (34, 34)
    s = drop_scenario(0.05, ny=8)
    s = dataclasses.replace(s, plate=dataclasses.replace(s.plate, n_modes=20))
    model = build_model(s)
    assert model.plate.n_modes < model.plate.n_red and not model.plate.truncated
    assert model.config.face_skin == 0.0 and len(model.plate_arrays.face_y) == 0
    with pytest.raises(
        SimulationError,
        match=r"granule 'g' .* reached the plate's face .*plate.n_modes = 0"
        r".*plate.modes = \"truncated\"",
    ):
        simulate(s, model=model, progress=False)


def test_contacts_formed_and_rebuilds_are_recorded_when_and_where_they_happen():
    """A granule in free flight towards the face: its patch contact forms within one step
    after its surface comes within skin R of the face (t = (gap - skin R) / vx), at its
    height y0 + vy t then; the lists are rebuilt every skin R / 2 of travel (3 times)."""
    gap, vx, vy, t_end = 2.0003e-3, 1.0, 0.5, 1.6e-3  # the crossing inside a step
    s = drop_scenario(0.05, vx=vx, vy=vy, gap=gap, t_end=t_end, out=1e-5)
    skin = s.contact.skin
    ds = simulate(s, progress=False)
    t_cross = (gap - skin * R) / vx
    assert list(ds.contact.values) == ["g"]
    t_formed = float(ds.contact_time_formed.values[0])
    assert 0.0 <= t_formed - t_cross <= float(ds.dt_max.max())
    assert ds.contact_y.values[0] == pytest.approx(0.05 + vy * t_formed, rel=1e-12)
    travel = np.hypot(vx, vy) * t_end
    assert ds.attrs["n_rebuilds"] == int(travel // (0.5 * skin * R)) == 3
    assert ds.contact_normal_force.values.max() == 0.0  # formed, not yet touched


@pytest.mark.parametrize("scheme", ["paper", "implicit"])
def test_a_patch_contact_added_starts_from_the_modes(scheme):
    """A patch contact added on a moving plate: its displacement and velocity are
    Phi_d q and Phi_d q' on its new rows; the paper scheme's Newmark interpolation starts
    from a_n = Phi_d q'' there, the implicit scheme keeps no acceleration."""
    model = build_model(drop_scenario(0.05, gap=6e-4, scheme=scheme))
    arr = driver.LoopArrays(model, np.array([0.0, 1e-6]), 0)
    lists = driver.ContactLists(model)
    lists.g = lists.g._replace(pc_x=lists.g.pc_x.copy())
    st = arr.st
    st.y[:] = model.initial_state
    arr.w.plate_free[:] = 1
    rng = np.random.default_rng(5)
    scale = 1.0 / np.sqrt(model.plate_arrays.omega2 / model.plate_arrays.omega2[0])
    st.q[:], st.qd[:], st.qdd[:] = (rng.normal(size=st.q.shape) * scale * f for f in (1e-9, 1e-6, 1e-3))
    assert driver.add_patch_contacts(model, lists, arr) == 1
    st, p = arr.st, arr.p
    assert np.allclose(st.u, p.phi_d @ st.q, rtol=1e-12, atol=0) and np.allclose(
        st.v, p.phi_d @ st.qd, rtol=1e-12, atol=0
    )
    expected = p.phi_d @ st.qdd if scheme == "paper" else np.zeros(2)
    assert np.abs(expected).max() > 0 or scheme == "implicit"
    assert np.allclose(st.a, expected, rtol=1e-12, atol=0)
    assert lists.changes().granule.tolist() == [0] and lists.changes().y.tolist() == [0.05]


def test_granule_touching_between_nodes_at_t0_bounces_as_one_reaching_the_face():
    """A granule touching the face between nodes at t = 0 gets its patch contact before the
    first step and bounces as the same granule reaching that spot from a gap (the patch
    formed during the run): restitution, force peak and the plate's energy, eq. (11) held."""
    touch_s = drop_scenario(BETWEEN, gap=0.0, t_end=5e-4)
    model = build_model(touch_s)
    assert len(model.plate_contacts) == 0 and list(model.initial_patches) == [0]
    touch = simulate(touch_s, model=model, progress=False)
    gap = simulate(drop_scenario(BETWEEN, t_end=1e-3), progress=False)
    b_t, b_g = bounce(touch), bounce(gap)
    assert list(touch.contact.values) == ["g"] and touch.contact_y.values[0] == pytest.approx(BETWEEN)
    assert touch.contact_normal_force.values[1, 0] > 0.0  # in touch from the first step
    assert b_t["e"] == pytest.approx(b_g["e"], rel=1e-4)
    assert b_t["f_max"] == pytest.approx(b_g["f_max"], rel=1e-3)
    assert b_t["t_c"] == pytest.approx(b_g["t_c"], abs=1e-6)
    assert touch.E_plate.values[-1] == pytest.approx(gap.E_plate.values[-1], rel=1e-3)
    assert b_t["residual"] < 1e-5


def test_granule_touching_between_nodes_at_t0_on_a_truncated_basis():
    """The same granule on the truncated basis (its patch's static rows w^T R_face w set
    at t = 0): restitution and the plate's energy within 0.5% of the full basis, eq. (11) held."""
    fast = dict(gap=0.0, t_end=5e-4)
    full = simulate(drop_scenario(BETWEEN, **fast), progress=False)
    trunc_s = _truncated(drop_scenario(BETWEEN, **fast))
    model = build_model(trunc_s)
    assert model.plate.truncated and list(model.initial_patches) == [0]
    trunc = simulate(trunc_s, model=model, progress=False)
    b_f, b_t = bounce(full), bounce(trunc)
    assert b_t["e"] == pytest.approx(b_f["e"], rel=5e-3)
    assert trunc.E_plate.values[-1] == pytest.approx(full.E_plate.values[-1], rel=5e-3)
    assert b_t["residual"] < 1e-5


def test_initial_contacts_on_nodes_keep_their_rigid_layers():
    """Contacts at t = 0 on a face node keep the rigid layer (the paper's model), those between
    nodes become patch contacts, listed after the layers on the output's contact axis."""
    from granplate.setup.scenario import Granule

    s = drop_scenario(BETWEEN, gap=0.0, t_end=2e-5)
    on_node = Granule(x=X0 - 0.004, y=0.08, radius=0.004, material="steel", label="n", vx=1.0)
    s = dataclasses.replace(s, granules=(on_node, *s.granules))
    model = build_model(s)
    assert list(model.plate_contacts) == [0] and list(model.initial_patches) == [1]
    ds = simulate(s, model=model, progress=False)
    assert list(ds.contact.values) == ["n", "g"]
    assert list(ds.contact_y.values) == pytest.approx([0.08, BETWEEN])


def test_patches_at_t0_refused_only_where_patches_are_impossible():
    """Between nodes at t = 0: the paper scheme on a truncated basis keeps its refusal
    (solver.scheme); fixed detection is refused naming the granule and contact.detection."""
    from granplate.errors import ScenarioError

    s = _truncated(drop_scenario(BETWEEN, gap=0.0, scheme="paper"))
    with pytest.raises(ScenarioError, match=r"'solver.scheme' = 'paper': the truncated plate basis"):
        build_model(s)
    s = drop_scenario(BETWEEN, gap=0.0)
    s = dataclasses.replace(s, contact=dataclasses.replace(s.contact, detection="fixed"))
    with pytest.raises(
        ScenarioError,
        match=r"'contact.detection' = 'fixed': granule 'g' \(placed by "
        r"granules\[0\].x, granules\[0\].y, granules\[0\].radius",
    ):
        build_model(s)


def test_continuous_layout_radius_builds_and_a_remaining_refusal_names_the_granule_and_the_layout():
    """A lattice with a radius off the node spacing builds (patch contacts at t = 0); a refusal
    that remains names the granule's label and the layout fields that placed it, no contact index."""
    from granplate.errors import ScenarioError
    from granplate.setup.scenario import LatticeLayout, Plate, Scenario

    s = Scenario(layout=LatticeLayout(columns=2, radius=0.0093, column_radii=(0.0093, 0.0071)), plate=Plate(height=0.1))
    model = build_model(s)
    assert len(model.initial_patches) == 4 and len(model.plate_contacts) == 0
    bad = dataclasses.replace(s, plate=Plate(height=0.1, clamped_edges=("left",)))
    assert len(build_model(bad).initial_patches) == 4  # patches may sit by clamped nodes
    bad = dataclasses.replace(s, plate=Plate(height=0.1, n_modes=30))
    with pytest.raises(ScenarioError) as err:
        build_model(bad)
    msg = str(err.value)
    assert "granule 'c2r1' (placed by layout.columns, layout.radius, layout.column_radii;" in msg
    assert "contact 0" not in msg and err.value.field == "plate.n_modes"

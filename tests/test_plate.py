"""Tests of granplate.plate: the plane-stress Q8 plate, rigid layers, modes, cache."""

from __future__ import annotations

import dataclasses
import math
import sys

import numpy as np
import pytest
import scipy.sparse.linalg as spla
from scipy.optimize import brentq
from skfem import MeshQuad

from granplate import plate as gp
from granplate.errors import ScenarioError
from granplate.plate import EDGES
from granplate.setup import plate_checks
from granplate.setup.materials import LIBRARY
from granplate.setup.scenario import Granule, Load, Plate, Scenario
from granplate.setup.validate import validate

STEEL = LIBRARY["steel"]
X0 = 0.01 + 2 * math.sqrt(0.02**2 - 0.01**2) + 0.01  # the paper's plate position, R2 = R1
CONTACTS = (0.09, 0.07, 0.05, 0.03, 0.01)


@pytest.fixture(autouse=True)
def _private_cache(tmp_path, monkeypatch):
    """Every test writes its cache files into its own temporary directory."""
    monkeypatch.setenv("GRANPLATE_CACHE", str(tmp_path / "cache"))


@pytest.fixture(scope="module")
def paper_plate() -> gp.PlateModel:
    """The default plate with the five rigid layers of contacts A..E, all modes."""
    return gp.build_plate(Plate(), X0, CONTACTS, edge_load=(0.025, 0.05), cache=False)


def fixed_dofs(model: gp.PlateModel) -> np.ndarray:
    """Full dofs that T maps to nothing (the clamped ones)."""
    return np.flatnonzero(np.asarray(abs(model.T).sum(axis=1)).ravel() == 0)


# --------------------------------------------------------------------------------------
# 1. Beam theory
# --------------------------------------------------------------------------------------
def timoshenko_clamped_frequencies(E, G, rho, k, length, depth, n=3):
    """First n natural frequencies [Hz] of a clamped-clamped Timoshenko beam.

    Per unit thickness: A = depth, I = depth^3 / 12. W = C1 cosh(a y) + C2 sinh(a y) +
    C3 cos(b y) + C4 sin(b y), the section rotation follows from kGA (W'' - Phi') +
    rho A w^2 W = 0; W = Phi = 0 at both ends gives a 4 x 4 determinant in w.
    """
    A, I = depth, depth**3 / 12
    kGA, EI = k * G * A, E * I

    def det(w):
        a4 = kGA * EI
        a2 = w**2 * (kGA * rho * I + rho * A * EI)
        a0 = rho * A * w**2 * (rho * I * w**2 - kGA)
        disc = math.sqrt(a2**2 - 4 * a4 * a0)
        al = math.sqrt((-a2 + disc) / (2 * a4))
        be = math.sqrt((a2 + disc) / (2 * a4))
        c = rho * A * w**2 / kGA
        p, r = al + c / al, be - c / be  # Phi = p sinh, p cosh, -r sin, r cos
        ch, sh, co, si = math.cosh(al * length), math.sinh(al * length), math.cos(be * length), math.sin(be * length)
        m = np.array([[1, 0, 1, 0], [0, p, 0, r], [ch, sh, co, si], [p * sh, p * ch, -r * si, r * co]])
        return np.linalg.det(m) / ch

    ws = np.linspace(2 * np.pi * 500.0, 2 * np.pi * 60e3, 3000)
    d = np.array([det(w) for w in ws])
    roots = [brentq(det, ws[i], ws[i + 1], xtol=1e-10) for i in np.flatnonzero(np.sign(d[:-1]) != np.sign(d[1:]))]
    return np.array(roots[:n]) / (2 * np.pi)


bending_frequencies = gp.transverse_mode_frequencies


def test_clamped_strip_matches_timoshenko_beam():
    """Clamped-clamped strip: first three bending frequencies = Timoshenko beam theory within 1%.

    Strip 0.1 m long (y), 0.01 m deep (x), plane stress, E and G = E / (2 (1 + nu)),
    Cowper's shear coefficient k = 10 (1 + nu) / (12 + 11 nu) of a narrow (plane-stress)
    rectangle. The 4 x 40 mesh is converged: the 2 x 20 mesh differs by < 0.5% (checked
    here) and an 8 x 80 mesh by < 0.1% (0.02 / 0.06 / 0.08% for modes 1-3), so the 1%
    tolerance covers the mesh error plus the model-form gap between 2D elasticity and
    Timoshenko theory at L/h = 10 (0.33 / 0.41 / 0.52% here; 0.4 / 0.6 / 0.8% with
    k = 5/6). Euler-Bernoulli is off by 6 / 14 / 23%: the shear effect is captured.
    """
    E, nu, rho = STEEL.E, STEEL.nu, STEEL.rho
    G = E / (2 * (1 + nu))
    k = 10 * (1 + nu) / (12 + 11 * nu)
    strip = Plate(width=0.01, height=0.1, nx=4, ny=40, clamped_edges=("top", "bottom"), n_modes=12)
    fe = bending_frequencies(gp.build_plate(strip, 0.0, [], cache=False))
    coarse = bending_frequencies(gp.build_plate(dataclasses.replace(strip, nx=2, ny=20), 0.0, [], cache=False))
    timo = timoshenko_clamped_frequencies(E, G, rho, k, 0.1, 0.01)
    beta_l = np.array([4.730040745, 7.853204624, 10.99560784])
    euler = beta_l**2 / 0.1**2 * math.sqrt(E * 0.01**2 / (12 * rho)) / (2 * np.pi)

    assert np.all(np.abs(coarse / fe - 1) < 5e-3), (coarse, fe)
    err_timo = np.abs(fe / timo - 1)
    err_euler = np.abs(fe / euler - 1)
    assert np.all(err_timo < 0.01), (fe, timo)
    assert err_euler[2] > 0.10 and err_euler[2] > 10 * err_timo[2], (fe, euler, timo)
    assert 4.5e3 < fe[0] < 5.5e3


def test_truncated_modes_are_the_lowest_of_the_full_set():
    """Keeping n_modes gives the same lowest frequencies and modes as keeping them all."""
    small = Plate(nx=2, ny=10)
    full = gp.build_plate(small, 0.0, [0.05], cache=False)
    some = gp.build_plate(dataclasses.replace(small, n_modes=5), 0.0, [0.05], cache=False)
    assert some.Phi.shape == (full.n_red, 5)
    np.testing.assert_allclose(some.omega, full.omega[:5], rtol=1e-9)
    M_r = (some.T.T @ some.mass_matrix() @ some.T).toarray()
    np.testing.assert_allclose(some.Phi.T @ M_r @ full.Phi[:, :5], np.eye(5), atol=1e-7)


# --------------------------------------------------------------------------------------
# 2. Mass, stiffness, connectivity
# --------------------------------------------------------------------------------------
def test_mass_and_rigid_motions(paper_plate):
    """u^T M u = rho t area for a rigid translation; rigid translations and rotation give K u = 0."""
    m = paper_plate
    M, K = m.mass_matrix(), m.stiffness_matrix()
    x, y = m.node_xy[:, 0], m.node_xy[:, 1]
    one, zero = np.ones_like(x), np.zeros_like(x)
    mass = STEEL.rho * 0.001 * 0.01 * 0.1
    for u in (np.column_stack([one, zero]).ravel(), np.column_stack([zero, one]).ravel()):
        assert u @ (M @ u) == pytest.approx(mass, rel=1e-13)
    scale = abs(K).max()
    for u in (
        np.column_stack([one, zero]).ravel(),
        np.column_stack([zero, one]).ravel(),
        np.column_stack([-(y - 0.05), x - X0]).ravel(),
    ):
        assert np.abs(K @ u).max() <= 1e-13 * scale * np.abs(u).max()
    # and a non-rigid field is not in the kernel (the check above can fail)
    u = np.column_stack([x - X0, zero]).ravel()
    assert np.abs(K @ u).max() > 1e-3 * scale * np.abs(u).max()


def test_vtk_connectivity(paper_plate):
    """elements: 4 corners anticlockwise then the midpoints of edges 01, 12, 23, 30 of the same element."""
    m = paper_plate
    xy = m.node_xy[m.elements]  # (n_elem, 8, 2)
    c = xy[:, :4]
    area = 0.5 * np.sum(c[..., 0] * np.roll(c[..., 1], -1, 1) - np.roll(c[..., 0], -1, 1) * c[..., 1], axis=1)
    np.testing.assert_allclose(area, 0.0025**2, rtol=1e-9)
    np.testing.assert_allclose(xy[:, 4:], 0.5 * (c + np.roll(c, -1, axis=1)), atol=1e-15)
    local = m.basis.element_dofs[::2].T // 2  # nodes of each element as scikit-fem sees them
    assert all(set(a) == set(b) for a, b in zip(m.elements, local))
    assert m.elements.shape == (160, 8)
    # symmetry line: 2 nx + 1 nodes on y = 0.05, left to right
    np.testing.assert_allclose(m.node_xy[m.symmetry_nodes, 1], 0.05, atol=1e-15)
    np.testing.assert_allclose(m.node_xy[m.symmetry_nodes, 0], X0 + np.linspace(0, 0.01, 9), atol=1e-15)


# --------------------------------------------------------------------------------------
# 3. Patch test and stress recovery
# --------------------------------------------------------------------------------------
def _distorted_mesh(nx=4, ny=5, seed=1):
    """A 1 x 1.2 rectangle whose interior vertices are moved by up to 20% of a cell."""
    mesh = MeshQuad.init_tensor(np.linspace(0, 1, nx + 1), np.linspace(0, 1.2, ny + 1))
    p = mesh.p.copy()
    inner = (p[0] > 1e-9) & (p[0] < 1 - 1e-9) & (p[1] > 1e-9) & (p[1] < 1.2 - 1e-9)
    rng = np.random.default_rng(seed)
    p[:, inner] += rng.uniform(-0.2, 0.2, (2, inner.sum())) * np.array([[1 / nx], [1.2 / ny]])
    return MeshQuad(p, mesh.t)


def test_patch_test_distorted_mesh():
    """Linear Dirichlet data on a distorted mesh: the solution is the linear field; strains exact."""
    mesh = _distorted_mesh()
    basis = gp.q8_basis(mesh)
    D = gp.plane_stress_matrix(STEEL.E, STEEL.nu)
    K = gp.assemble_stiffness(basis, D, 0.001)
    op = gp.strain_operator(basis)
    xy = gp.node_coordinates(basis)
    a, B = np.array([1e-4, -2e-4]), np.array([[1e-3, 4e-4], [-3e-4, 2e-3]])
    exact = (a + xy @ B.T).ravel()
    boundary = basis.get_dofs().flatten()
    inner = np.setdiff1d(np.arange(basis.N), boundary)
    u = np.zeros(basis.N)
    u[boundary] = exact[boundary]
    u[inner] = spla.spsolve(K[inner][:, inner].tocsc(), -K[inner][:, boundary] @ u[boundary])
    assert np.abs(u - exact).max() <= 1e-10 * np.abs(exact).max()
    assert inner.size > 0
    eps = (op @ exact).reshape(3, -1)
    want = np.array([B[0, 0], B[1, 1], B[0, 1] + B[1, 0]])
    assert np.abs(eps - want[:, None]).max() <= 1e-12 * np.abs(want).max()


def test_strain_recovery_order_and_von_mises():
    """strain_op rows are [component][element][qp] at qp_xy; von Mises of uniaxial / shear states."""
    free = Plate(width=0.01, height=0.02, nx=2, ny=4, clamped_edges=())
    m = gp.build_plate(free, 0.0, [], cache=False)
    x, y = m.node_xy[:, 0], m.node_xy[:, 1]
    # quadratic field, exactly representable on rectangles: u = (x^2, x y)
    u = np.column_stack([x**2, x * y]).ravel()
    exx, eyy, gxy = (m.strain_op @ u).reshape(3, *m.qp_xy.shape[:2])
    qx, qy = m.qp_xy[..., 0], m.qp_xy[..., 1]
    np.testing.assert_allclose(exx, 2 * qx, rtol=1e-12, atol=1e-16)
    np.testing.assert_allclose(eyy, qx, rtol=1e-12, atol=1e-16)
    np.testing.assert_allclose(gxy, qy, rtol=1e-12, atol=1e-16)
    assert m.qp_xy.shape == (8, 9, 2)

    # through modal coordinates (all modes of an unconstrained plate: q = Phi^T M x)
    M = m.mass_matrix()
    sigma, nu, E = 1e8, STEEL.nu, STEEL.E
    uniaxial = np.column_stack([sigma / E * x, -nu * sigma / E * y]).ravel()  # sxx = sigma only
    shear = np.column_stack([1e-4 * y, np.zeros_like(x)]).ravel()  # gamma_xy = 1e-4
    q = np.stack([m.Phi.T @ (M @ uniaxial), m.Phi.T @ (M @ shear)])
    np.testing.assert_allclose(m.full_displacement(q)[0].ravel(), uniaxial, rtol=0, atol=1e-9 * np.abs(uniaxial).max())
    vm = m.von_mises(q)
    assert vm.shape == (2, 8, 9)
    np.testing.assert_allclose(vm[0], sigma, rtol=1e-8)
    np.testing.assert_allclose(vm[1], math.sqrt(3) * E / (2 * (1 + nu)) * 1e-4, rtol=1e-8)


# --------------------------------------------------------------------------------------
# 4. Rigid layers
# --------------------------------------------------------------------------------------
def test_rigid_layer_transmits_the_full_force(paper_plate):
    """Static K_r x = f at a driving dof: clamp reactions balance (Fx, Fy); layer nodes move with it."""
    m = paper_plate
    K = m.stiffness_matrix()
    K_r = (m.T.T @ K @ m.T).tocsc()
    F = np.array([3.0e3, -1.7e3])
    for k in (0, 2):
        f = np.zeros(m.n_red)
        f[m.drive_dofs[k]] = F
        x = m.T @ spla.spsolve(K_r, f)
        r = K @ x  # nodal forces the plate needs: applied loads + reactions
        fixed = fixed_dofs(m)
        reaction = np.array([r[fixed[fixed % 2 == 0]].sum(), r[fixed[fixed % 2 == 1]].sum()])
        # sum of all nodal forces is zero (K kills translations): reactions = -F
        np.testing.assert_allclose(reaction + F, 0.0, atol=1e-9 * np.abs(F).max())
        # the layer: left-edge nodes within w/2 = 1.25 mm of y_k, all with the driving node's motion
        u = x.reshape(-1, 2)
        left = np.flatnonzero(np.abs(m.node_xy[:, 0] - X0) < 1e-12)
        layer = left[np.abs(m.node_xy[left, 1] - CONTACTS[k]) <= 0.00125 + 1e-12]
        assert layer.size == 3
        np.testing.assert_array_equal(u[layer], np.broadcast_to(u[layer[0]], (3, 2)))
        assert np.all(u[layer, 0] > 0) and np.all(u[layer, 1] < 0)
        outside = left[np.abs(m.node_xy[left, 1] - CONTACTS[k]) > 0.002]
        assert not np.any(np.all(u[outside] == u[layer[0]], axis=1))
        # the forces on the layer nodes add up to F (internal constraint forces cancel)
        np.testing.assert_allclose(r.reshape(-1, 2)[layer].sum(axis=0), F, rtol=1e-8)


def test_rigid_layer_width_option():
    """rigid_layer_width = w slaves exactly the left-edge nodes with |y - y_k| <= w/2."""
    for w, n_layer in ((1e-4, 1), (0.0025, 3), (0.005, 5)):
        m = gp.build_plate(Plate(rigid_layer_width=w, n_modes=1), X0, [0.05], cache=False)
        n_nodes = m.node_xy.shape[0]
        assert m.n_red == 2 * n_nodes - 36 - 2 * (n_layer - 1)


# --------------------------------------------------------------------------------------
# 5. Modes, energy, compliance
# --------------------------------------------------------------------------------------
def test_modes_energy_and_compliance(paper_plate):
    """Phi^T M_r Phi = I, Phi^T K_r Phi = diag(omega^2); energy() and compliance() from M_r, K_r directly."""
    m = paper_plate
    K, M = m.stiffness_matrix(), m.mass_matrix()
    K_r = (m.T.T @ K @ m.T).toarray()
    M_r = (m.T.T @ M @ m.T).toarray()
    assert m.n_modes == m.n_red == 1082
    assert np.all(np.diff(m.omega) >= 0)
    np.testing.assert_allclose(m.Phi.T @ M_r @ m.Phi, np.eye(m.n_modes), atol=1e-8)
    w2 = m.omega**2
    assert np.abs(m.Phi.T @ K_r @ m.Phi - np.diag(w2)).max() <= 1e-8 * w2.max()

    rng = np.random.default_rng(7)
    q = rng.normal(size=(2, m.n_modes)) * 1e-7 / np.maximum(m.omega, 1.0)
    qdot = rng.normal(size=(2, m.n_modes)) * 1e-4
    x = m.full_dofs(q)
    v = m.full_dofs(qdot)
    direct = 0.5 * np.einsum("bi,bi->b", v, (M @ v.T).T) + 0.5 * np.einsum("bi,bi->b", x, (K @ x.T).T)
    np.testing.assert_allclose(m.energy(q, qdot), direct, rtol=1e-8)

    for dt in (4e-8, 1e-6):
        inv = np.linalg.inv(M_r + dt**2 * K_r / 4)
        idx = m.drive_dofs.ravel()
        np.testing.assert_allclose(
            m.compliance(dt), inv[np.ix_(idx, idx)], rtol=1e-7, atol=1e-9 * abs(inv[np.ix_(idx, idx)]).max()
        )
    # tangential c_k at the paper's step: ~1e5 1/kg (effective mass ~1e-5 kg)
    c_t = np.diag(m.compliance(4e-8))[1::2]
    assert np.all((5e4 < c_t) & (c_t < 2e5))


# --------------------------------------------------------------------------------------
# 6. Edge load
# --------------------------------------------------------------------------------------
@pytest.mark.parametrize("y0, L", [(0.025, 0.05), (0.0231, 0.0437)])
def test_edge_load_resultant_and_moment(y0, L):
    """Consistent nodal forces: sum = 2L/pi, first moment = (2L/pi)(y0 + L/2), even with load ends inside elements."""
    m = gp.build_plate(Plate(n_modes=20), X0, CONTACTS, edge_load=(y0, L), cache=False)
    f = m.edge_load_full.reshape(-1, 2)
    assert np.all(f[:, 1] == 0.0)
    loaded = np.flatnonzero(f[:, 0] != 0.0)
    assert np.all(np.abs(m.node_xy[loaded, 0] - X0) < 1e-12)
    assert np.all((m.node_xy[loaded, 1] > y0 - 0.00125 - 1e-12) & (m.node_xy[loaded, 1] < y0 + L + 0.00125 + 1e-12))
    resultant = 2 * L / np.pi
    assert f[:, 0].sum() == pytest.approx(resultant, rel=1e-10)
    assert (f[:, 0] * m.node_xy[:, 1]).sum() == pytest.approx(resultant * (y0 + L / 2), rel=1e-10)
    np.testing.assert_allclose(m.edge_load_modal, m.Phi.T @ (m.T.T @ m.edge_load_full), rtol=1e-12, atol=1e-14)


def test_no_edge_load_is_zero():
    """edge_load=None gives zero load vectors of the right shapes."""
    m = gp.build_plate(Plate(n_modes=3), X0, CONTACTS, cache=False)
    assert m.edge_load_full.shape == (m.n_full,) and not np.any(m.edge_load_full)
    assert m.edge_load_modal.shape == (3,) and not np.any(m.edge_load_modal)


# --------------------------------------------------------------------------------------
# 7. Bad inputs: scenarios refused by validation, direct callers by the plate layer
# --------------------------------------------------------------------------------------
def plate_scenario(contacts, radius: float = 0.002, **plate) -> Scenario:
    """A plate at X0 with one steel granule touching its left edge at each height in contacts."""
    granules = tuple(
        Granule(x=X0 - radius, y=y, radius=radius, material="steel", label=f"g{k}") for k, y in enumerate(contacts)
    )
    return Scenario(granules=granules, plate=Plate(x0=X0, **plate), load=Load(kind="none"))


def refusal(scenario: Scenario) -> ScenarioError:
    """The ScenarioError validate raises for scenario (fails the test when there is none)."""
    with pytest.raises(ScenarioError) as err:
        validate(scenario)
    return err.value


def test_contact_between_nodes_is_a_patch_where_patches_are_possible():
    """A contact at t = 0 between face nodes: accepted (a patch contact) with dynamic detection on
    all modes; refused with fixed detection or a cut dense basis, naming the field, the granule and
    the spacing."""
    s = plate_scenario((0.09, 0.0712))
    validate(s)
    assert plate_checks.split_initial_contacts(s) == ([0], [1])
    err = refusal(dataclasses.replace(s, contact=dataclasses.replace(s.contact, detection="fixed")))
    assert err.field == "contact.detection" and err.value == "fixed"
    assert "granule 'g1'" in str(err) and "between face nodes" in str(err) and "0.0712" in str(err)
    assert "0.00125" in str(err) and "contact 1" not in str(err)
    err = refusal(plate_scenario((0.09, 0.0712), n_modes=20))
    assert err.field == "plate.n_modes" and "granule 'g1'" in str(err)
    validate(plate_scenario((0.09, 0.07125), n_modes=20))  # on a midside node: a rigid layer


def test_validation_refuses_odd_ny():
    """Odd plate.ny (no node row on the symmetry line y = height/2): ScenarioError naming plate.ny."""
    err = refusal(plate_scenario((), ny=41))
    assert err.field == "plate.ny" and err.value == 41 and "must be even" in str(err)
    validate(plate_scenario((), ny=42))


def test_validation_refuses_overlapping_rigid_layers():
    """Rigid layers of neighbouring contacts that share a node: ScenarioError naming plate.rigid_layer_width."""
    err = refusal(plate_scenario(CONTACTS, rigid_layer_width=0.02))
    assert err.field == "plate.rigid_layer_width" and err.value == 0.02
    assert "granule 'g0' (placed by granules[0].x, granules[0].y, granules[0].radius;" in str(err)
    assert "at y=0.09 m and granule 'g1'" in str(err) and "at y=0.07 m share" in str(err)
    validate(plate_scenario(CONTACTS, rigid_layer_width=0.0175))  # 7 nodes each, none shared


def test_validation_refuses_contacts_and_layers_on_clamps():
    """A contact on a clamped node or a layer reaching one: ScenarioError naming the clamp or the width."""
    err = refusal(plate_scenario((0.05,), clamped_edges=("left",)))
    assert err.field == "plate.clamped_edges" and "granule 'g0' (placed by" in str(err)
    assert "touches the plate at y=0.05 m, on a clamped node" in str(err)
    err = refusal(plate_scenario((0.0025,), rigid_layer_width=0.005))
    assert err.field == "plate.rigid_layer_width" and "reaches a clamped node" in str(err)
    validate(plate_scenario((0.0025,), rigid_layer_width=0.0025))  # reaches y = 0.00125, not y = 0
    validate(plate_scenario((0.0025,), rigid_layer_width=0.005, clamped_edges=("top",)))


@pytest.mark.parametrize("clamped", [("top", "bottom"), (), ("left",), ("top", "right"), EDGES])
def test_reduced_dof_count_matches_the_built_plate(clamped):
    """validate's count of reduced dofs = the built plate's n_red, for several clamps and layers."""
    contacts = () if "left" in clamped else (0.05, 0.025)
    for plate in (
        Plate(nx=2, ny=10, clamped_edges=clamped),
        Plate(nx=3, ny=12, clamped_edges=clamped, rigid_layer_width=0.02),
    ):
        s = plate_scenario(
            contacts, **{k: getattr(plate, k) for k in ("nx", "ny", "clamped_edges", "rigid_layer_width")}
        )
        n_slaved = sum(len(m) for _, m in plate_checks.rigid_layers(s.plate, list(contacts)))
        m = gp.build_plate(s.plate, X0, contacts, cache=False, symmetry_line=False)
        assert plate_checks.reduced_dof_count(s.plate, n_slaved) == m.n_red


def test_validation_refuses_too_many_modes():
    """plate.n_modes above the reduced dofs: ScenarioError with the allowed range 0..n_red; n_red itself passes."""
    n_red = 2 * (569 - 18 - 10)  # paper plate: 569 nodes, 18 clamped, 2 slaved per layer of 5
    validate(plate_scenario(CONTACTS, n_modes=n_red))
    err = refusal(plate_scenario(CONTACTS, n_modes=n_red + 1))
    assert err.field == "plate.n_modes" and f"1..{n_red}" in str(err)


def test_plate_contacts_are_the_granules_facing_the_left_edge():
    """A granule farther than neighbour_gap * R from the plate, or beyond its height, is not a plate contact."""
    s = plate_scenario((0.05,))
    far = Granule(x=X0 - 0.01, y=0.0712, radius=0.002, material="steel", label="far")  # gap 4 R
    above = Granule(x=X0 - 0.002, y=0.11, radius=0.002, material="steel", label="above")
    s = dataclasses.replace(s, granules=s.granules + (far, above))
    assert plate_checks.plate_contact_heights(s) == [0.05]
    validate(s)  # 0.0712 is between nodes, but that granule does not touch the plate


def test_build_plate_refuses_inconsistent_inputs():
    """A direct caller's bad contacts, layers, clamps or sizes: PlateError (not ScenarioError) naming the input."""
    cases = [
        (Plate(), (0.09, 0.0712), "plate.ny"),
        (Plate(rigid_layer_width=0.02), CONTACTS, "plate.rigid_layer_width"),
        (Plate(), (0.0,), "plate.clamped_edges"),
        (Plate(clamped_edges=("left",)), (0.05,), "plate.clamped_edges"),
        (Plate(rigid_layer_width=0.005), (0.0025,), "plate.rigid_layer_width"),
        (Plate(), (0.15,), "plate.y0"),
        (Plate(n_modes=10**6), CONTACTS, "plate.n_modes"),
        (Plate(clamped_edges=("front",)), CONTACTS, "plate.clamped_edges"),
        (Plate(thickness=0.0), CONTACTS, "plate.thickness"),
        (Plate(material="unobtainium"), CONTACTS, "plate.material"),
    ]
    for plate, contacts, name in cases:
        with pytest.raises(gp.PlateError) as err:
            gp.build_plate(plate, X0, contacts, cache=False)
        assert err.value.name == name and not isinstance(err.value, ScenarioError), (plate, contacts, err.value)
    odd = Plate(ny=41, n_modes=2)
    with pytest.raises(gp.PlateError, match="must be even"):
        gp.build_plate(odd, X0, [], cache=False)
    assert gp.build_plate(odd, X0, [], cache=False, symmetry_line=False).symmetry_nodes.size == 0


# --------------------------------------------------------------------------------------
# 8. Cache
# --------------------------------------------------------------------------------------
def _arrays(m: gp.PlateModel) -> dict[str, np.ndarray]:
    return {
        "Phi": m.Phi,
        "omega": m.omega,
        "T.data": m.T.data,
        "T.indices": m.T.indices,
        "T.indptr": m.T.indptr,
        "strain_op.data": m.strain_op.data,
        "strain_op.indices": m.strain_op.indices,
        "strain_op.indptr": m.strain_op.indptr,
        "edge_load_full": m.edge_load_full,
        "edge_load_modal": m.edge_load_modal,
        "drive_dofs": m.drive_dofs,
        "phi_drive": m.phi_drive,
        "node_xy": m.node_xy,
        "qp_xy": m.qp_xy,
    }


def test_cache_roundtrip_and_corrupt_file(tmp_path, monkeypatch):
    """A cached build loads (no eigen-solve) identical arrays; a corrupt cache file is recomputed."""
    from granplate.plate.build import forget_built_plates

    cache_dir = tmp_path / "here"
    monkeypatch.setenv("GRANPLATE_CACHE", str(cache_dir))
    plate = Plate(nx=2, ny=20)
    args = (plate, X0, CONTACTS[1:4], (0.025, 0.05))
    fresh = gp.build_plate(*args)
    files = list((cache_dir / "plate").glob("*.npz"))
    assert len(files) == 1

    real_modal_basis = gp.modal_basis

    def must_not_solve(*a, **k):
        raise AssertionError("modal_basis called although the cache holds the result")

    monkeypatch.setattr(sys.modules[gp.build_plate.__module__], "modal_basis", must_not_solve)
    forget_built_plates()  # the store's copy, not the one this process keeps
    cached = gp.build_plate(*args)
    a, b = _arrays(fresh), _arrays(cached)
    for name in a:
        assert a[name].dtype == b[name].dtype and np.array_equal(a[name], b[name]), name
    assert np.array_equal(cached.compliance(4e-8), fresh.compliance(4e-8))

    # other inputs -> another key (and a solve)
    with pytest.raises(AssertionError, match="modal_basis called"):
        gp.build_plate(*args, material=dataclasses.replace(STEEL, E=210e9))

    # corrupt file -> recomputed, identical, file repaired
    files[0].write_bytes(b"this is not an npz file")
    calls = []

    def counting(*a, **k):
        calls.append(1)
        return real_modal_basis(*a, **k)

    monkeypatch.setattr(sys.modules[gp.build_plate.__module__], "modal_basis", counting)
    forget_built_plates()
    repaired = gp.build_plate(*args)
    assert calls == [1]
    c = _arrays(repaired)
    for name in a:
        assert np.array_equal(a[name], c[name]), name
    forget_built_plates()
    again = gp.build_plate(*args)
    assert calls == [1]
    assert np.array_equal(again.Phi, fresh.Phi)

    # cache=False neither reads nor writes
    for f in (cache_dir / "plate").glob("*.npz"):
        f.unlink()
    gp.build_plate(*args, cache=False)
    assert calls == [1, 1] and not list(cache_dir.rglob("*.npz"))


def test_mode_sign_rule_is_deterministic_for_symmetric_modes():
    """A mode and its negative get the same sign, also when its largest entries tie in magnitude."""
    phi = np.array([[1.0, 0.5], [-1.0, 0.5], [0.3, -2.0], [-0.3, 0.1]])  # column 0: +-1 tie
    fixed = gp.fix_mode_signs(phi)
    np.testing.assert_array_equal(gp.fix_mode_signs(-phi), fixed)
    np.testing.assert_array_equal(np.abs(fixed), np.abs(phi))
    assert np.all(gp.sign_reference(4) @ fixed > 0)


def test_a_plate_asked_again_is_kept_and_equals_a_fresh_build():
    """The process keeps a built plate (the same object for the same inputs) and it equals,
    array for array, a plate built afresh (without the store) from the same inputs; other
    inputs build another plate."""
    from granplate.plate.build import forget_built_plates

    plate = Plate(nx=2, ny=10, n_modes=8)
    first = gp.build_plate(plate, X0, [0.05], edge_load=(0.025, 0.05))
    assert gp.build_plate(plate, X0, [0.05], edge_load=(0.025, 0.05)) is first
    assert gp.build_plate(plate, X0, [0.03], edge_load=(0.025, 0.05)) is not first
    fresh = gp.build_plate(plate, X0, [0.05], edge_load=(0.025, 0.05), cache=False)
    forget_built_plates()
    again = gp.build_plate(plate, X0, [0.05], edge_load=(0.025, 0.05))
    assert again is not first
    for f in dataclasses.fields(first):
        a, b = getattr(first, f.name), getattr(fresh, f.name)
        if isinstance(a, np.ndarray):
            np.testing.assert_array_equal(a, b, err_msg=f.name)
        elif hasattr(a, "toarray"):
            np.testing.assert_array_equal(a.toarray(), b.toarray(), err_msg=f.name)
        elif isinstance(a, (int, float, str)) and f.name != "arrays_key":
            assert a == b, f.name
    assert first.arrays_key == again.arrays_key != ""


def test_a_run_leaves_the_kept_plate_unchanged():
    """The loop writes into its own copies: after a run the kept plate's arrays are those
    it was built with."""
    import granplate

    s = granplate.with_changes(granplate.preset("steel-r1"), {"time.t_end": 2e-6})
    plate = granplate.build_model(s).plate
    before = {n: np.array(getattr(plate, n)) for n in ("Phi", "omega", "phi_drive", "phi_face", "edge_load_modal")}
    granplate.simulate(s, progress=False)
    assert granplate.build_model(s).plate is plate
    for n, v in before.items():
        np.testing.assert_array_equal(getattr(plate, n), v, err_msg=n)


def test_the_plate_package_loads_its_members_on_first_use():
    """Truth: a fresh interpreter's sys.modules: the plate maxima (what reading a result
    needs) load without scikit-fem; asking the package for build_plate loads it."""
    import subprocess

    probe = (
        "import sys\nimport granplate.plate.peaks\nprint('skfem' in sys.modules)\n"
        "from granplate.plate import build_plate\nprint('skfem' in sys.modules)"
    )
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["False", "True"]

"""The body's fields after a 3D run (granplate.results.body) against brute force: the
displacement at field times is Phi q plus the static residual from a dense solve of K; the
quasi-static modal response plus the residual is K^-1 f; the per-time maxima are those of
the fields evaluated time by time; a uniform stress's ball average is that stress; the
VTK node order puts the mid-nodes at VTK's edge midpoints in positively oriented cells."""

from __future__ import annotations

import numpy as np
import pytest

from granplate.results.body import BODY_SUMMARY, body_data, body_operators, field_indices
from granplate.setup.scenario import Solid
from granplate.solid.build import build_solid
from granplate.solid.fe import node_coordinates, scalar_basis, stiffness_matrix
from granplate.solid.mesh import box_mesh
from granplate.solid.stress import elasticity_matrix, strain_operator, von_mises
from granplate.solid.surface import closest_point, patch_weights
from granplate.solid.vtk_cells import VTK_REFERENCE, boundary_faces, frame_volume, vtk_connectivity

SIZE = (0.04, 0.04, 0.01)
N_T = 41
TIMES = np.linspace(0.0, 2e-4, N_T)
#: The constant contact force on the top face [N] and where it acts [m].
FORCE = np.array([3.0, -2.0, -40.0])
AT = (0.023, 0.017, 0.0101)
RADIUS = 0.008


@pytest.fixture(scope="module")
def solid():
    m = build_solid(
        Solid(size=SIZE, elements=(4, 4, 2), clamped=("xmin",), max_frequency=8e4), surface=None, cache=False
    )
    assert 10 <= m.n_modes <= 40
    return m


@pytest.fixture(scope="module")
def ops(solid):
    return body_operators(solid, RADIUS)


def contact(ops):
    """One granule on the top face at AT, pressing with FORCE at every output time."""
    cp = closest_point(ops.surface, AT)
    face = np.full((N_T, 1), cp.face)
    xi = np.broadcast_to(cp.xi, (N_T, 1, 2)).copy()
    return face, xi, np.broadcast_to(FORCE, (N_T, 1, 3)).copy(), cp


def dense_system(solid):
    K = stiffness_matrix(solid.basis, solid.material.E, solid.material.nu)[solid.dofs][:, solid.dofs].toarray()
    return K


def reduced_force(solid, ops, cp) -> np.ndarray:
    """The nodal force vector on the reduced dofs, from the face's patch weights."""
    dofs, w = patch_weights(ops.surface, cp.face, cp.xi)
    f = np.zeros(3 * solid.nodes.shape[0])
    np.add.at(f, dofs.ravel(), (w[:, None] * FORCE[None, :]).ravel())
    return f[solid.dofs]


def full(solid, u_red: np.ndarray) -> np.ndarray:
    u = np.zeros((3 * solid.nodes.shape[0],) + u_red.shape[1:])
    u[solid.dofs] = u_red
    return u


def modal_history(solid) -> np.ndarray:
    """q = a mode's shape times sin(omega t): mode 2 at amplitude 1e-4 kg^1/2 m."""
    q = np.zeros((N_T, solid.n_modes))
    q[:, 2] = 1e-4 * np.sin(solid.omega[2] * TIMES)
    return q


def test_displacement_is_modes_plus_the_static_residual(solid, ops):
    """body_u at the field times = Phi q + K^-1 f - Phi diag(1/omega^2) Phi^T f (dense solve)."""
    face, xi, force, cp = contact(ops)
    q = modal_history(solid)
    data, coords = body_data(solid, q, q, TIMES, face, xi, force, 8, RADIUS, operators=ops)
    f = reduced_force(solid, ops, cp)
    static = np.linalg.solve(dense_system(solid), f) - solid.Phi @ ((solid.Phi.T @ f) / solid.omega**2)
    idx = field_indices(N_T, 8)
    assert list(idx) == [0, 8, 16, 24, 32, 40]
    assert np.allclose(coords["field_time"][1], TIMES[idx])
    expected = full(solid, solid.Phi @ q[idx].T + static[:, None]).reshape(-1, 3, len(idx))
    got = np.stack([data[f"body_u{c}"].values for c in "xyz"], axis=1)  # (field_time, 3, node)
    assert np.allclose(got, expected.transpose(2, 1, 0), rtol=0, atol=1e-10 * np.abs(expected).max())
    assert data["body_ux"].dims == ("field_time", "body_node") and data["body_ux"].attrs["units"] == "m"
    assert data["body_von_mises"].dims == ("field_time", "body_element")


@pytest.mark.parametrize("element", ["hex20", "hex27", "tet10"])
def test_quasi_static_modes_plus_residual_is_the_static_solution(solid, ops, element):
    """q = diag(1/omega^2) Phi^T f (every kept mode quasi-static) plus the residual = K^-1 f to 1e-8."""
    if element != "hex20":
        solid = build_solid(
            Solid(size=SIZE, elements=(3, 3, 1), element=element, clamped=("xmin",), max_frequency=8e4),
            surface=None,
            cache=False,
        )
        ops = body_operators(solid, RADIUS)
    face, xi, force, cp = contact(ops)
    f = reduced_force(solid, ops, cp)
    q = np.broadcast_to((solid.Phi.T @ f) / solid.omega**2, (N_T, solid.n_modes)).copy()
    data, _ = body_data(solid, q, q, TIMES, face, xi, force, 100, RADIUS, operators=ops)
    exact = full(solid, np.linalg.solve(dense_system(solid), f)).reshape(-1, 3)
    got = np.stack([data[f"body_u{c}"].values[-1] for c in "xyz"], axis=1)
    assert np.abs(got - exact).max() <= 1e-8 * np.abs(exact).max()
    assert data["max_displacement"].values[-1] == pytest.approx(np.linalg.norm(exact, axis=1).max(), rel=1e-8)


@pytest.mark.parametrize("off", [slice(0, N_T // 3), slice(5, None)])
def test_maxima_equal_the_fields_time_by_time(solid, ops, off):
    """max_von_mises, max_von_mises_ball and max_displacement at every output time equal a
    time-by-time evaluation: the dense static solve, the vector basis' strains, D, von Mises
    (a contact forming a third into the run: G's columns at its dofs; one touching at 5
    times only: a solve per time)."""
    face, xi, force, cp = contact(ops)
    face[off] = -1
    q = modal_history(solid)
    data, _ = body_data(solid, q, q, TIMES, face, xi, force, 4, RADIUS, operators=ops)
    K = dense_system(solid)
    f = reduced_force(solid, ops, cp)
    op, D = strain_operator(_vector_basis(solid)), elasticity_matrix(solid.material.E, solid.material.nu)
    x = np.linalg.solve(K, f)
    for k in range(N_T):
        on = float(face[k, 0] >= 0)
        u = full(solid, solid.Phi @ q[k] + on * (x - solid.Phi @ ((solid.Phi.T @ f) / solid.omega**2)))
        vm = von_mises(D @ (op @ u).reshape(6, -1))
        assert data["max_von_mises"].values[k] == pytest.approx(vm.max(), rel=1e-9)
        assert data["max_von_mises_ball"].values[k] == pytest.approx((ops.ball @ vm).max(), rel=1e-9)
        assert data["max_displacement"].values[k] == pytest.approx(
            np.linalg.norm(u.reshape(-1, 3), axis=1).max(), rel=1e-9
        )
    assert data["max_von_mises"].attrs["units"] == "Pa" and data["max_von_mises"].attrs["long_name"]


def _vector_basis(solid):
    from granplate.solid.fe import vector_basis

    return vector_basis(solid.mesh, solid.element)


@pytest.mark.parametrize("block_bytes", [None, 3 * 2**20])
def test_summary_only_holds_the_runs_maxima_bit_for_bit(solid, ops, block_bytes, monkeypatch):
    """summary_only: the three maxima alone, the exact route's values in the blocks it
    evaluates (bit for bit), NaN in blocks whose bound from the references cannot reach the
    run's largest value; the largest over the run equal (a decaying mode and a contact
    force that grows and falls: most blocks are skipped in small blocks)."""
    import granplate.results.body as body

    if block_bytes is not None:
        monkeypatch.setattr(body, "BLOCK_BYTES", block_bytes)
    n_t = 201
    t = np.linspace(0.0, 1e-3, n_t)
    cp = closest_point(ops.surface, AT)
    face = np.full((n_t, 1), cp.face)
    xi = np.broadcast_to(cp.xi, (n_t, 1, 2)).copy()
    force = FORCE[None, None, :] * np.sin(np.pi * t / 1e-3)[:, None, None]
    q = np.zeros((n_t, solid.n_modes))
    q[:, 0] = 1e-4 * np.exp(-t / 2e-4) * np.cos(solid.omega[0] * t)
    full_data, _ = body_data(solid, q, q, t, face, xi, force, 4, RADIUS, operators=ops)
    data, coords = body_data(solid, q, q, t, face, xi, force, 4, RADIUS, summary_only=True, operators=ops)
    assert set(data) == set(BODY_SUMMARY) and coords == {}
    for name in BODY_SUMMARY:
        got, exact = data[name].values, full_data[name].values
        known = np.isfinite(got)
        assert np.array_equal(got[known], exact[known])
        assert np.nanmax(got) == exact.max()
        if block_bytes is not None:
            assert known.sum() < n_t // 2


def test_interrupted(solid, ops):
    """A stop after the first block keeps the times of that block."""
    face, xi, force, _ = contact(ops)
    q = modal_history(solid)
    full_data, _ = body_data(solid, q, q, TIMES, face, xi, force, 4, RADIUS, operators=ops)
    import granplate.results.body as body

    old = body.BLOCK_BYTES
    body.BLOCK_BYTES = 1
    try:
        part, coords = body_data(
            solid, q, q, TIMES, face, xi, force, 4, RADIUS, operators=ops, should_stop=lambda: True
        )
    finally:
        body.BLOCK_BYTES = old
    assert part["max_von_mises"].sizes["time"] == 1 and part["body_ux"].sizes["field_time"] == 1
    assert part["max_von_mises"].values[0] == pytest.approx(full_data["max_von_mises"].values[0], rel=1e-12)


def test_ball_average_of_a_uniform_stress_is_that_stress(solid, ops):
    """u = eps (x, -nu y, -nu z): von Mises E eps at every point, and every ball's mean of it."""
    eps, nu, E = 1e-4, solid.material.nu, solid.material.E
    x = solid.nodes
    u = (eps * np.column_stack([x[:, 0], -nu * x[:, 1], -nu * x[:, 2]])).ravel()
    vm = von_mises(ops.D @ (ops.strain @ u).reshape(6, -1))
    assert np.allclose(vm, E * eps, rtol=1e-10)
    assert ops.ball.shape[0] > 0 and np.allclose(ops.ball @ vm, E * eps, rtol=1e-10)


@pytest.mark.parametrize("element", ["hex20", "hex27", "tet10"])
def test_vtk_order_mid_nodes_and_orientation(element):
    """In VTK order every mid-node sits at its reference point's image (edge midpoints, face
    centres, the centre), every cell is positively oriented, and the cells fill the box."""
    mesh = box_mesh([0.03, 0.02, 0.01], [3, 2, 2], tetrahedra=element == "tet10")
    sb = scalar_basis(mesh, element)
    cells = vtk_connectivity(sb, element)
    xyz = node_coordinates(sb)[cells]  # (n_cells, n, 3)
    ref = VTK_REFERENCE[element]
    a, b, c = (1, 2, 3) if element == "tet10" else (1, 3, 4)  # the corners at r = 1, s = 1, t = 1
    x0 = xyz[:, :1]
    frame = np.stack([xyz[:, a] - xyz[:, 0], xyz[:, b] - xyz[:, 0], xyz[:, c] - xyz[:, 0]], axis=1)  # (cells, 3, 3)
    assert np.allclose(xyz, x0 + np.einsum("kr,erx->ekx", ref, frame), atol=1e-15)  # affine cells
    vol = frame_volume(xyz, element)
    assert np.all(vol > 0.0)
    total = vol.sum() / (6.0 if element == "tet10" else 1.0)
    assert total == pytest.approx(0.03 * 0.02 * 0.01, rel=1e-12)
    faces, owner = boundary_faces(cells, element)
    assert len(faces) == len(mesh.boundary_facets()) and np.all(owner >= 0)
    p = node_coordinates(sb)[faces]  # (n_faces, k, 3): VTK's faces are outward
    normal = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    centre = node_coordinates(sb)[cells[owner]].mean(axis=1)
    assert np.all(np.sum(normal * (p.mean(axis=1) - centre), axis=1) > 0.0)


def test_free_body_static_part_is_inertia_relief():
    """A body held nowhere: quasi-static elastic modes plus the residual = the inertia-relief
    displacement (I - Phi_r Phi_r^T M) K^+ (I - M Phi_r Phi_r^T) f, K^+ the dense pseudo-inverse."""
    from granplate.solid.fe import mass_matrix

    m = build_solid(Solid(size=SIZE, elements=(3, 3, 1), max_frequency=8e4), surface=None, cache=False)
    assert m.free and np.all(m.omega[:6] == 0.0) and m.n_modes > 6
    ops = body_operators(m, RADIUS)
    face, xi, force, cp = contact(ops)
    f = reduced_force(m, ops, cp)
    q = np.zeros((N_T, m.n_modes))
    q[:, 6:] = (m.Phi[:, 6:].T @ f) / m.omega[6:] ** 2
    data, _ = body_data(m, q, q, TIMES, face, xi, force, 100, RADIUS, operators=ops)
    K = dense_system(m)
    M = mass_matrix(m.basis, m.material.rho)[m.dofs][:, m.dofs].toarray()
    R = m.Phi[:, :6]
    x = np.linalg.pinv(K, rcond=1e-12, hermitian=True) @ (f - M @ R @ (R.T @ f))
    exact = full(m, x - R @ (R.T @ (M @ x))).reshape(-1, 3)
    got = np.stack([data[f"body_u{c}"].values[-1] for c in "xyz"], axis=1)
    assert np.abs(got - exact).max() <= 1e-7 * np.abs(exact).max()

"""The solid's modes: a free body's six rigid-body modes at zero exactly, M-orthonormal
modes, the windows against a dense eigensolver, a clamped thin plate against Leissa."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as la

from granplate.solid.boundary import fixed_dofs, free_dofs, reduced
from granplate.solid.fe import mass_matrix, node_coordinates, scalar_basis, stiffness_matrix
from granplate.solid.mesh import box_mesh
from granplate.solid.modes import modes_below, rigid_body_modes

E, NU, RHO = 200e9, 0.3, 7850.0


def system(size, elements, element="hex20", clamped=(), rollers=()):
    mesh = box_mesh(size, elements, tetrahedra=element == "tet10")
    s = scalar_basis(mesh, element)
    dofs = free_dofs(3 * s.N, fixed_dofs(s, mesh, clamped, rollers))
    nodes = node_coordinates(s)
    K = reduced(stiffness_matrix(s, E, NU), dofs)
    M = reduced(mass_matrix(s, RHO), dofs)
    return K, M, nodes, dofs


def test_free_box_keeps_six_rigid_modes():
    """A box held nowhere: six modes at omega = 0 exactly, then elastic ones; Phi^T M Phi = I."""
    K, M, nodes, dofs = system([0.02, 0.01, 0.005], [2, 2, 1])
    omega, Phi = modes_below(K, M, 2 * np.pi * 3e5, nodes[dofs // 3], rigid=rigid_body_modes(nodes))
    assert np.all(omega[:6] == 0.0) and omega[6] > 1e5
    assert np.abs(Phi.T @ (M @ Phi) - np.eye(len(omega))).max() < 1e-10
    assert np.abs(K @ Phi[:, :6]).max() < 1e-9 * abs(K).max() * 0.02


def test_windows_find_every_mode_of_the_dense_solver():
    """Many small windows find the dense LAPACK spectrum below the cut-off, no mode lost or
    repeated, each mode equal up to sign (distinct frequencies)."""
    K, M, nodes, dofs = system([0.03, 0.02, 0.004], [3, 2, 1], clamped=("xmin",))
    lam, vec = la.eigh(K.toarray(), M.toarray())
    cut = np.sqrt(lam[25] * lam[26])
    omega, Phi = modes_below(K, M, np.sqrt(cut), nodes[dofs // 3], k=6)
    assert len(omega) == 26
    assert np.allclose(omega**2, lam[:26], rtol=1e-9)
    distinct = np.flatnonzero(np.minimum(np.diff(lam[:27])[1:], np.diff(lam[:27])[:-1]) > 1e-6 * lam[1:26]) + 1
    dots = np.abs(np.einsum("ij,ij->j", Phi[:, distinct], M @ vec[:, distinct]))
    assert np.allclose(dots, 1.0, atol=1e-8)


def test_modes_are_deterministic():
    """Two builds give the same modes bitwise, each signed by the plate's rule (a positive
    projection on the fixed reference vector)."""
    K, M, nodes, dofs = system([0.03, 0.02, 0.004], [3, 2, 1], clamped=("xmin",))
    a = modes_below(K, M, 2 * np.pi * 2e5, nodes[dofs // 3])
    b = modes_below(K, M, 2 * np.pi * 2e5, nodes[dofs // 3])
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
    from granplate.plate.modes import sign_reference

    assert np.all(sign_reference(a[1].shape[0]) @ a[1] > 0)


@pytest.mark.parametrize("element,n,tol", [("hex20", 10, 0.04), ("hex27", 8, 0.04)])
def test_clamped_thin_plate_against_leissa(element, n, tol):
    """A clamped square plate (a/h = 50): first frequency lambda^2/a^2 sqrt(D/(rho h)),
    lambda^2 = 35.99 (Leissa), within a few percent on a modest mesh."""
    a, h = 0.1, 0.002
    K, M, nodes, dofs = system([a, a, h], [n, n, 1], element, clamped=("xmin", "xmax", "ymin", "ymax"))
    D = E * h**3 / (12 * (1 - NU**2))
    reference = 35.99 / a**2 * np.sqrt(D / (RHO * h))
    omega, _ = modes_below(K, M, 1.2 * reference, nodes[dofs // 3])
    assert omega[0] == pytest.approx(reference, rel=tol)


def test_rollers_fix_the_normal_dof_only():
    """A roller on zmin fixes the z dofs of its nodes and nothing else."""
    mesh = box_mesh([0.02, 0.01, 0.005], [2, 1, 1])
    s = scalar_basis(mesh, "hex20")
    fixed = fixed_dofs(s, mesh, rollers=("zmin",))
    z = node_coordinates(s)[fixed // 3, 2]
    assert np.all(fixed % 3 == 2) and np.allclose(z, 0.0) and len(fixed) == 13


def test_one_blas_thread_limits_and_restores():
    """Inside one_blas_thread every BLAS library reports one thread; after it, its former count."""
    threadpoolctl = pytest.importorskip("threadpoolctl")
    from granplate.solid.factor import one_blas_thread

    before = [p["num_threads"] for p in threadpoolctl.threadpool_info() if p["user_api"] == "blas"]
    with one_blas_thread():
        inside = [p["num_threads"] for p in threadpoolctl.threadpool_info() if p["user_api"] == "blas"]
    after = [p["num_threads"] for p in threadpoolctl.threadpool_info() if p["user_api"] == "blas"]
    assert inside and all(n == 1 for n in inside) and after == before


def test_windows_side_by_side_find_the_dense_spectrum_as_one_by_one():
    """Two planned windows solved at once on a pool give the dense LAPACK spectrum below
    the cut-off (no mode lost or repeated), the same pairs bitwise as one by one; a plan
    whose second shift lies too high to reach the first window's cut is dropped, and the
    windows one by one still find every mode."""
    from concurrent.futures import ThreadPoolExecutor

    K, M, nodes, dofs = system([0.03, 0.02, 0.004], [3, 2, 1], clamped=("xmin",))
    lam, _ = la.eigh(K.toarray(), M.toarray())
    cut = np.sqrt(lam[25] * lam[26])
    xyz = nodes[dofs // 3]
    plan = ((None, 14), (lam[19], 14))
    with ThreadPoolExecutor(max_workers=2) as pool:
        side = modes_below(K, M, np.sqrt(cut), xyz, k=8, plan=plan, pool=pool)
    alone = modes_below(K, M, np.sqrt(cut), xyz, k=8, plan=plan)
    assert len(side[0]) == 26 and np.allclose(side[0] ** 2, lam[:26], rtol=1e-9)
    assert np.array_equal(side[0], alone[0]) and np.array_equal(side[1], alone[1])
    too_high = modes_below(K, M, np.sqrt(cut), xyz, k=8, plan=((None, 6), (lam[60], 6)))
    assert len(too_high[0]) == 26 and np.allclose(too_high[0] ** 2, lam[:26], rtol=1e-9)


def test_split_plan_shifts_the_second_window_between_the_estimate_and_the_cut_off():
    """Below SPLIT_VALUES one window; from it on two, the first asking its share, the
    second shifted halfway (in omega^2) between the estimated top of the first and the
    cut-off, asking the rest and the overlap."""
    from granplate.solid.modes import SPLIT_LOW_SHARE, SPLIT_OVERLAP, SPLIT_VALUES, split_plan

    assert split_plan(SPLIT_VALUES - 1, 4.0, lambda c: 1.0) == ((None, SPLIT_VALUES - 1),)
    (s0, k0), (s1, k1) = split_plan(200, 4.0, lambda c: c / 100.0)
    low = int(SPLIT_LOW_SHARE * 200)
    assert s0 is None and k0 == low and s1 == 0.5 * (low / 100.0 + 4.0)
    assert k1 == 200 - low + int(SPLIT_OVERLAP * 200)


@pytest.mark.parametrize("rollers", [(), ("zmin",)])
def test_mass_operator_is_the_mass_matrix_product(rollers):
    """M x by the scalar mass on each node's dofs equals M's own product (whole nodes kept)
    and falls back to it where rollers fix single dofs."""
    from granplate.solid.modes import mass_operator

    K, M, nodes, dofs = system([0.03, 0.02, 0.004], [3, 2, 1], clamped=("xmin",), rollers=rollers)
    x = np.random.default_rng(3).standard_normal(M.shape[0])
    assert np.allclose(mass_operator(M) @ x, M @ x, rtol=1e-13, atol=0.0)

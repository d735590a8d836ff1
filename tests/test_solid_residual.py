"""The residual compliance: modal truncation plus R equals the full static solution on
the chosen dofs, R vanishes with every mode kept, and a free body's inertia-relief
flexibility equals the dense constrained solution."""

from __future__ import annotations

import numpy as np
import scipy.linalg as la

from granplate.solid.boundary import face_node_dofs, fixed_dofs, free_dofs, reduced, reduced_index
from granplate.solid.fe import mass_matrix, node_coordinates, scalar_basis, stiffness_matrix
from granplate.solid.mesh import box_mesh
from granplate.solid.modes import m_orthonormal, modes_below, rigid_body_modes
from granplate.solid.residual import flexibility, flexibility_block, residual_compliance

E, NU, RHO = 200e9, 0.3, 7850.0


def system(clamped):
    mesh = box_mesh([0.03, 0.02, 0.004], [3, 2, 1])
    s = scalar_basis(mesh, "hex20")
    dofs = free_dofs(3 * s.N, fixed_dofs(s, mesh, clamped))
    K = reduced(stiffness_matrix(s, E, NU), dofs)
    M = reduced(mass_matrix(s, RHO), dofs)
    top = reduced_index(dofs, face_node_dofs(s, mesh, "zmax", "surface")[:, 2])
    return K, M, node_coordinates(s), dofs, top[top >= 0]


def test_truncation_plus_residual_is_the_static_solution():
    """Phi_S Omega^-2 Phi_S^T F + R F = (K^-1 F)_S for a load F on the top face's z dofs (1e-10)."""
    K, M, nodes, dofs, top = system(("xmin",))
    omega, Phi = modes_below(K, M, 2 * np.pi * 1e5, nodes[dofs // 3])
    R = residual_compliance(K, top, Phi, omega, nodes[dofs // 3])
    F = np.random.default_rng(1).standard_normal(len(top))
    f = np.zeros(K.shape[0])
    f[top] = F
    exact = la.solve(K.toarray(), f)[top]
    modal = Phi[top] @ ((Phi[top].T @ F) / omega**2) + R @ F
    assert np.abs(modal - exact).max() < 1e-10 * np.abs(exact).max()


def test_residual_vanishes_with_every_mode():
    """With all modes kept (dense eigensolver) R = 0 to rounding."""
    K, M, nodes, dofs, top = system(("xmin",))
    lam, Phi = la.eigh(K.toarray(), M.toarray())
    R = residual_compliance(K, top, Phi, np.sqrt(lam), nodes[dofs // 3])
    G = la.inv(K.toarray())[np.ix_(top, top)]
    assert np.abs(R).max() < 1e-8 * np.abs(G).max()


def test_free_body_inertia_relief():
    """Free body: the elastic modes' share plus R equals x solving K x = P f with
    Phi_r^T M x = 0 (the dense constrained system), P f = f - M Phi_r Phi_r^T f."""
    K, M, nodes, dofs, top = system(())
    xyz = nodes[dofs // 3]
    omega, Phi = modes_below(K, M, 2 * np.pi * 2e5, xyz, rigid=rigid_body_modes(nodes))
    R = residual_compliance(K, top, Phi, omega, xyz, M=M, rigid=Phi[:, :6])
    F = np.random.default_rng(2).standard_normal(len(top))
    f = np.zeros(K.shape[0])
    f[top] = F
    Pr = m_orthonormal(rigid_body_modes(nodes), M)
    MR = M @ Pr
    n = K.shape[0]
    A = np.block([[K.toarray(), MR], [MR.T, np.zeros((6, 6))]])
    exact = la.solve(A, np.concatenate([f - MR @ (Pr.T @ f), np.zeros(6)]))[:n][top]
    el = Phi[top][:, 6:]
    modal = el @ ((el.T @ F) / omega[6:] ** 2) + R @ F
    assert np.abs(modal - exact).max() < 1e-9 * np.abs(exact).max()


def test_block_solves_equal_the_schur_complement():
    """G[S, S] from unit-load block solves (chunked) equals the Schur complement's inverse."""
    K, M, nodes, dofs, top = system(("xmin",))
    omega = np.array([])
    R = residual_compliance(K, top, np.zeros((K.shape[0], 0)), omega, nodes[dofs // 3])
    G = flexibility_block(flexibility(K, nodes[dofs // 3]), K.shape[0], top, chunk=7)
    assert np.abs(R - G).max() < 1e-10 * np.abs(G).max()

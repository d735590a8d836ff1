"""The solid's stress recovery (granplate.solid.stress) against closed forms: uniaxial
stress and pure shear exactly at every quadrature point, the ball mean of a linear field at
the centre, and the ball mean's convergence to the exact one under refinement."""

from __future__ import annotations

import numpy as np
import pytest
from skfem import Basis, ElementHex2, ElementHexS2, ElementTetP2, ElementVector, MeshHex, MeshTet

from granplate.errors import ScenarioError
from granplate.solid.stress import (
    ball_average_operator,
    ball_operator,
    max_ball_von_mises,
    ball_mean,
    ball_von_mises,
    elasticity_matrix,
    max_von_mises,
    modal_unit_stresses,
    point_spacing,
    quadrature_points,
    quadrature_weights,
    strain_operator,
    strains,
    stresses,
    surface_centres,
    von_mises,
    von_mises_of_ball_mean,
)

E, NU = 200e9, 0.3
ELEMENTS = {"hex20": (MeshHex, ElementHexS2), "hex27": (MeshHex, ElementHex2), "tet10": (MeshTet, ElementTetP2)}


def basis_of(name: str, refine: int = 1, intorder: int | None = None) -> Basis:
    mesh_type, element = ELEMENTS[name]
    kw = {} if intorder is None else {"intorder": intorder}
    return Basis(mesh_type().refined(refine), ElementVector(element()), **kw)


def interpolate(basis: Basis, u) -> np.ndarray:
    """The nodal interpolant of u(x) -> (3, n) (the Lagrange dofs: the field at each dof's
    location, component of each dof from the element layout, local dof 3 j + c)."""
    comp = np.empty(basis.N, dtype=np.int64)
    for i in range(basis.element_dofs.shape[0]):
        comp[basis.element_dofs[i]] = i % 3
    values = np.asarray(u(basis.doflocs))
    return values[comp, np.arange(basis.N)]


@pytest.mark.parametrize("name", list(ELEMENTS))
def test_uniaxial_and_shear_closed_forms(name):
    """u = eps (x, -nu y, -nu z) gives sigma_xx = E eps, the rest 0, von Mises E eps; u =
    gamma/2 (y, x, 0) gives tau_xy = G gamma, von Mises sqrt(3) G gamma: at every point."""
    basis = basis_of(name)
    op, D = strain_operator(basis), elasticity_matrix(E, NU)
    eps = 1e-3
    s = stresses(D, strains(op, interpolate(basis, lambda x: eps * np.stack([x[0], -NU * x[1], -NU * x[2]]))))
    expected = np.zeros(6)
    expected[0] = E * eps
    assert np.allclose(s, expected[:, None], rtol=0, atol=1e-9 * E * eps)
    assert np.allclose(von_mises(s), E * eps, rtol=1e-12)
    gamma = 2e-3
    s = stresses(D, strains(op, interpolate(basis, lambda x: 0.5 * gamma * np.stack([x[1], x[0], 0 * x[2]]))))
    G = E / (2 * (1 + NU))
    expected = np.zeros(6)
    expected[5] = G * gamma
    assert np.allclose(s, expected[:, None], rtol=0, atol=1e-9 * G * gamma)
    assert np.isclose(max_von_mises(s), np.sqrt(3) * G * gamma, rtol=1e-12)


def test_modal_unit_stresses_are_linear():
    """Modal unit stresses: the stress of a combination of modes is the combination of theirs."""
    basis = basis_of("tet10")
    op, D = strain_operator(basis), elasticity_matrix(E, NU)
    Phi = np.random.default_rng(3).normal(size=(basis.N, 4))
    unit = modal_unit_stresses(op, D, Phi)
    q = np.array([0.5, -1.0, 2.0, 0.25])
    assert unit.shape == (4, 6, op.shape[0] // 6)
    assert np.allclose(np.einsum("m,mcp->cp", q, unit), stresses(D, strains(op, Phi @ q)))


def test_ball_mean_of_a_linear_field_is_its_centre_value():
    """The ball mean of a linear stress field (a quadratic displacement) is the field at the
    centre: the partial-cell weights are symmetric about a centre of symmetry of the mesh."""
    basis = basis_of("hex20", refine=2)
    op, D = strain_operator(basis), elasticity_matrix(E, NU)
    u = lambda x: 1e-3 * np.stack([x[0] ** 2 + x[1] * x[2], x[1] ** 2 - x[0] * x[2], x[0] * x[1] + x[2] ** 2])
    sigma = stresses(D, strains(op, interpolate(basis, u)))
    points, weights = quadrature_points(basis), quadrature_weights(basis)
    centre = np.array([[0.5, 0.5, 0.5], [0.25, 0.75, 0.5]])
    ball = ball_average_operator(points, weights, centre, 0.2, point_spacing(basis))
    x = centre.T
    grad = 1e-3 * np.array([[2 * x[0], x[2], x[1]], [-x[2], 2 * x[1], -x[0]], [x[1], x[0], 2 * x[2]]])
    eps_c = np.stack(
        [grad[0, 0], grad[1, 1], grad[2, 2], grad[1, 2] + grad[2, 1], grad[0, 2] + grad[2, 0], grad[0, 1] + grad[1, 0]]
    )
    assert np.allclose(ball_mean(ball, sigma), D @ eps_c, rtol=0, atol=1e-12 * E * 1e-3)
    # von Mises is a norm: the von Mises of the mean never exceeds the mean von Mises
    assert np.all(von_mises_of_ball_mean(ball, sigma) <= ball_von_mises(ball, sigma) * (1 + 1e-12))


def exact_field(x):
    """A smooth displacement [m] outside the element space, and its gradient."""
    a = 1e-3
    u = a * np.stack([np.sin(2 * x[0] + x[1]), np.cos(x[0] - x[2]), np.sin(x[1] * x[2])])
    g = a * np.array(
        [
            [2 * np.cos(2 * x[0] + x[1]), np.cos(2 * x[0] + x[1]), 0 * x[0]],
            [-np.sin(x[0] - x[2]), 0 * x[0], np.sin(x[0] - x[2])],
            [0 * x[0], x[2] * np.cos(x[1] * x[2]), x[1] * np.cos(x[1] * x[2])],
        ]
    )
    return u, g


def exact_ball_von_mises(centre, radius, D):
    """The ball mean of the exact von Mises stress: Gauss-Legendre in r and cos(theta),
    the trapezoid rule in phi (spectrally accurate for this smooth field)."""
    r, wr = np.polynomial.legendre.leggauss(16)
    c, wc = np.polynomial.legendre.leggauss(16)
    r, wr = 0.5 * radius * (r + 1), 0.5 * radius * wr
    phi = np.linspace(0, 2 * np.pi, 32, endpoint=False)
    R, C, P = np.meshgrid(r, c, phi, indexing="ij")
    W = (wr[:, None, None] * R**2) * wc[None, :, None] * (2 * np.pi / 32)
    S = np.sqrt(1 - C**2)
    x = np.stack([centre[0] + R * S * np.cos(P), centre[1] + R * S * np.sin(P), centre[2] + R * C])
    _, g = exact_field(x.reshape(3, -1))
    eps = np.stack([g[0, 0], g[1, 1], g[2, 2], g[1, 2] + g[2, 1], g[0, 2] + g[2, 0], g[0, 1] + g[1, 0]])
    vm = von_mises(D @ eps)
    return float((vm * W.ravel()).sum() / W.sum())


def test_ball_mean_converges_under_refinement():
    """The ball mean of the von Mises stress of a smooth field's interpolant converges to the
    exact ball mean on 2, 4, 8 hex20 per side, monotonically (observed order 2.07: relative
    errors 4.5e-2, 4.7e-3, 2.5e-3; 5.5e-4 on 16 per side, left out here for speed)."""
    D = elasticity_matrix(E, NU)
    centre, radius = np.array([0.45, 0.52, 0.48]), 0.3
    exact = exact_ball_von_mises(centre, radius, D)
    errors = []
    for refine in (1, 2, 3):
        basis = basis_of("hex20", refine, intorder=4)
        sigma = stresses(D, strains(strain_operator(basis), interpolate(basis, lambda x: exact_field(x)[0])))
        ball = ball_average_operator(
            quadrature_points(basis), quadrature_weights(basis), centre[None], radius, point_spacing(basis)
        )
        errors.append(abs(ball_von_mises(ball, sigma)[0] - exact) / exact)
    order = np.polyfit(np.log([1, 0.5, 0.25]), np.log(errors), 1)[0]
    assert errors[2] < errors[1] < errors[0] and errors[-1] < 3e-3 and order > 1.8, (errors, order)


def test_surface_centres_lie_on_the_boundary():
    """The surface centres are the boundary nodes: on a face of the unit cube, each once."""
    x = surface_centres(basis_of("tet10"))
    assert np.all(np.isclose(x, 0).any(axis=1) | np.isclose(x, 1).any(axis=1))
    assert len(x) == 6 * 5 * 5 - 12 * 5 + 8  # the nodes of a 5 x 5 node grid on each side


def test_surface_maximum_of_a_uniform_field():
    """A uniform uniaxial stress: every ball mean about the surface nodes, cut or not, is E eps,
    so the surface maximum is E eps; a radius <= 0 is a ScenarioError naming it."""
    basis = basis_of("hex27")
    sigma = stresses(
        elasticity_matrix(E, NU),
        strains(strain_operator(basis), interpolate(basis, lambda x: 1e-3 * np.stack([x[0], -NU * x[1], -NU * x[2]]))),
    )
    for partial in (True, False):
        ball = ball_operator(basis, surface_centres(basis), 0.2, partial_cells=partial)
        assert np.allclose(ball_von_mises(ball, sigma), E * 1e-3, rtol=1e-12)
        assert np.isclose(max_ball_von_mises(ball, sigma), E * 1e-3, rtol=1e-12)
    with pytest.raises(ScenarioError, match="stress_radius"):
        ball_operator(basis, surface_centres(basis), 0.0)

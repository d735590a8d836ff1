"""build_model: the loop's arrays from a scenario, against hand-computed values."""

from __future__ import annotations

import math

import numpy as np
import pytest

from conftest import sphere_on_wall, two_spheres
from granplate.model.arrays import build_model
from granplate.model.inputs import SCHEME_IMPLICIT, SCHEME_NAMES, SCHEME_PAPER, scheme_number
from granplate.physics.contact import COEF_A, COEF_C, COEF_KS, COEF_MU
from granplate.setup.io import with_changes

STEEL_E, STEEL_NU, STEEL_RHO = 200e9, 0.30, 7850.0


def test_two_granules_hertz_coefficients_by_hand():
    """Two steel spheres R = 1 cm: one pair with A = 4/3 E* sqrt(R*) (eq. 3, E* of eq. 4),
    c = alpha_n sqrt(m* A), mu and k_s of the scenario; masses and inertias of spheres."""
    alpha = 0.05
    m = build_model(two_spheres(0.1, alpha_n=alpha))
    r = 0.01
    mass = 4.0 / 3.0 * math.pi * r**3 * STEEL_RHO
    e_star = 1.0 / (2.0 * (1.0 - STEEL_NU**2) / STEEL_E)
    a = 4.0 / 3.0 * e_star * math.sqrt(r / 2.0)
    g = m.granular
    assert m.pairs.tolist() == [[0, 1]]
    np.testing.assert_allclose(g.mass, [mass, mass], rtol=1e-14)
    np.testing.assert_allclose(g.inertia, [0.4 * mass * r * r] * 2, rtol=1e-14)
    row = g.pair_coef[0]
    assert row[COEF_A] == pytest.approx(a, rel=1e-14)
    assert row[COEF_C] == pytest.approx(alpha * math.sqrt(mass / 2.0 * a), rel=1e-14)
    assert row[COEF_MU] == pytest.approx(0.099) and row[COEF_KS] == pytest.approx(1000.0)
    assert len(g.wall_i) == 0 and len(g.pc_i) == 0 and len(m.plate_arrays.omega2) == 0
    np.testing.assert_array_equal(m.initial_state[:, 3], [0.1, -0.1])


def test_wall_contact_against_rigid_body():
    """A steel sphere on a rigid floor: A = 4/3 E/(1 - nu^2) sqrt(R) (rigid body: eq. 4
    with the wall term zero), c = alpha_n sqrt(m A); outward normal stored unit."""
    m = build_model(sphere_on_wall(0.0, -0.1, alpha_n=0.02))
    r = 0.01
    mass = 4.0 / 3.0 * math.pi * r**3 * STEEL_RHO
    a = 4.0 / 3.0 * STEEL_E / (1.0 - STEEL_NU**2) * math.sqrt(r)
    row = m.granular.wall_coef[0]
    assert row[COEF_A] == pytest.approx(a, rel=1e-14)
    assert row[COEF_C] == pytest.approx(0.02 * math.sqrt(mass * a), rel=1e-14)
    np.testing.assert_allclose(m.granular.wall_geo[0], [0.0, -1.0, 0.0])


def test_scheme_numbering():
    """Config.scheme is the index of solver.scheme in SCHEME_NAMES; unknown names refused."""
    assert SCHEME_NAMES[SCHEME_PAPER] == "paper" and SCHEME_NAMES[SCHEME_IMPLICIT] == "implicit"
    for name in SCHEME_NAMES:
        m = build_model(with_changes(two_spheres(0.1), {"solver.scheme": name}))
        assert m.config.scheme == scheme_number(name)
    with pytest.raises(ValueError, match="allowed"):
        scheme_number("leapfrog")

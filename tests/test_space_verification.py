"""The verification of spheres in space (granplate.verification.space_cases; the cases
themselves run in tests/test_verification.py): the helpers against geometry, and the
conservation check shown able to fail."""

from __future__ import annotations

import numpy as np
import pytest

from granplate.setup.validate import validate
from granplate.verification import space_cases as S
from granplate.verification.base import load_case_scenario, simulate


def test_in_space_is_a_rotation_of_the_plane():
    """in_space along (2, 3, 6)/7 keeps every distance between centres, every speed and
    every spin's size, and puts the chain on the line s = x e."""
    plane = load_case_scenario("striker-chain")
    tilted = S.in_space(plane, S.DIAGONAL)
    validate(tilted)
    p2 = np.array([[g.x, g.y, 0.0] for g in plane.granules])
    p3 = np.array([[g.x, g.y, g.z] for g in tilted.granules])
    d2 = np.linalg.norm(p2[:, None] - p2[None], axis=-1)
    d3 = np.linalg.norm(p3[:, None] - p3[None], axis=-1)
    assert np.allclose(d3, d2, rtol=0, atol=4 * np.finfo(float).eps * d2.max())  # a few ulps
    assert np.allclose(p3, np.outer(p2[:, 0], S.DIAGONAL), rtol=0, atol=4 * np.finfo(float).eps * d2.max())
    v3 = np.array([[g.vx, g.vy, g.vz] for g in tilted.granules])
    assert np.allclose(np.linalg.norm(v3, axis=1), [abs(g.vx) for g in plane.granules], rtol=1e-15)
    assert tilted.dimension == 3 and all(len(g.spin()) == 3 for g in tilted.granules)


def test_in_space_refuses_walls():
    """Only free granules are mapped: a plane scenario with walls is refused naming them."""
    with pytest.raises(ValueError, match="walls, plate, layout: in_space maps free granules only"):
        S.in_space(load_case_scenario("wall-bounce"))


def test_momenta_of_a_rigid_rotation():
    """momenta: two unit masses at (+-1, 0, 0) moving at (0, +-1, 0), unit spins about z
    with I = 1: P = 0, L = (0, 0, 2 + 2) (orbital 2, spin 2)."""
    pos = np.array([[[1.0, 0, 0], [-1.0, 0, 0]]])
    vel = np.array([[[0, 1.0, 0], [0, -1.0, 0]]])
    spin = np.array([[[0, 0, 1.0], [0, 0, 1.0]]])
    p, ang = S.momenta(np.ones(2), np.ones(2), pos, vel, spin)
    assert np.array_equal(p[0], [0.0, 0.0, 0.0]) and np.array_equal(ang[0], [0.0, 0.0, 4.0])


def test_radius_arm_does_not_conserve_angular_momentum():
    """The free assembly with the paper's torque arm R instead of the contact point's:
    the angular momentum drifts by far more than the case's tolerance (each sliding pair
    adds a couple f delta), so the case's check can fail; the momentum still holds."""
    s = load_case_scenario("3d-free-assembly", {"contact.torque_arm": "radius"})
    ds = simulate(s)
    m, inertia, _ = S.masses(s)
    pos, vel, spin = S.state_3d(ds)
    p, ang = S.momenta(m, inertia, pos, vel, spin)
    scale = float((m * np.linalg.norm(pos[0], axis=-1)).sum()) * float(np.linalg.norm(vel[0], axis=-1).max())
    assert np.abs(ang - ang[0]).max() / scale > 1e-9
    assert np.abs(p - p[0]).max() / (m.sum() * np.linalg.norm(vel[0], axis=-1).max()) < 1e-12


def test_fcc_block_is_face_centred_cubic():
    """fcc_block: nearest neighbours exactly 2R apart, twelve of them around an interior
    site (the FCC coordination number), the x = 0 face alone launched."""
    from granplate.verification.lammps import fcc_block

    s = fcc_block(2, radius=1e-3)
    validate(s)
    p = np.array([[g.x, g.y, g.z] for g in s.granules])
    d = np.linalg.norm(p[:, None] - p[None], axis=-1)
    np.fill_diagonal(d, np.inf)
    assert d.min() == pytest.approx(2e-3, rel=1e-14)
    centre = int(np.argmin(np.linalg.norm(p - p.mean(axis=0), axis=1)))
    assert int(np.sum(np.isclose(d[centre], 2e-3, rtol=1e-12))) == 12
    assert {g.vx for g in s.granules if g.x == 0.0} == {1.0} and {g.vx for g in s.granules if g.x > 0} == {0.0}


def test_gas_in_box_starts_without_contacts():
    """gas_in_box: the seeded gas touches nothing at t = 0 (validated), its walls are the
    six faces of a box holding every sphere, and its speeds reach the chosen bound."""
    from granplate.verification.lammps import gas_in_box

    s = gas_in_box()
    validate(s)
    p = np.array([[g.x, g.y, g.z] for g in s.granules])
    r = s.granules[0].radius
    d = np.linalg.norm(p[:, None] - p[None], axis=-1)
    np.fill_diagonal(d, np.inf)
    assert d.min() > 2 * r
    for w in s.walls:
        n = np.asarray(w.normal)
        assert (p @ n + r < w.offset).all()
    v = np.array([[g.vx, g.vy, g.vz] for g in s.granules])
    assert 0.9 < np.abs(v).max() <= 1.0
    assert len(s.granules) == 48 and len(s.walls) == 6


@pytest.mark.parametrize("name", ["3d-oblique", "3d-head-on", "3d-rolling", "3d-free-assembly", "3d-plastic"])
def test_space_scenarios_are_three_dimensional(name):
    """Each 3D verification scenario validates, is in space and leaves the plane z = 0 or
    spins about an axis other than z, so that it tests something the plane cannot."""
    s = load_case_scenario(name)
    assert s.dimension == 3
    off_plane = any(g.z != 0.0 or g.vz != 0.0 for g in s.granules)
    tilted_spin = any(any(c != 0.0 for c in g.spin()[:2]) for g in s.granules)
    assert off_plane or tilted_spin

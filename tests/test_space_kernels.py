"""The granular medium in space (solver.granular3d, physics.space) against the plane's
laws: a state in the plane z = 0 with spins along z gives the plane's forces, torques,
powers and energies (docs/model.md section 3.7); the slip vector and friction torques
against their definitions; the split friction's exact relaxation in space."""

from __future__ import annotations

import math

import numpy as np
import pytest

import granplate as gp
from granplate.model.arrays import build_model
from granplate.model.inputs import Granular3, no_history
from granplate.physics.space import (
    arm_torque_3d,
    friction_along_slip,
    friction_vector_3d,
    pair_contact_3d,
    pair_overlap_3d,
    slip_velocity_3d,
)
from granplate.solver import friction_space, granular as plane, granular3d as space


def planar_state():
    """The steel-r1 packing (its plate and load left out), every granule nudged and given
    a velocity and a spin (seeded), so that most contacts overlap and slide: the 2D model
    and its state (ng, 6)."""
    s = gp.with_changes(gp.preset("steel-r1"), {"load.kind": "none", "contact.mu": 0.3})
    m = build_model(s)
    g = m.granular
    ng = len(g.radius)
    rng = np.random.default_rng(7)
    y = m.initial_state.copy()
    y[:, 0] += rng.uniform(-1e-5, 1e-5, ng)
    y[:, 1] += rng.uniform(-1e-5, 1e-5, ng)
    y[:, 3:5] = rng.normal(0.0, 0.5, (ng, 2))
    y[:, 5] = rng.normal(0.0, 50.0, ng)
    e = np.zeros(0, np.int64)
    g = g._replace(
        pc_i=e,
        pc_x=np.zeros(0),
        pc_coef=np.zeros((0, g.pc_coef.shape[1])),
        pc_hist=no_history(0),
        pair_hist=no_history(len(g.pair_ij)),
        wall_hist=no_history(len(g.wall_i)),
    )
    return m, g, y


def lifted(g, y):
    """The same medium and state in space: z = 0, spins along z, walls with nz = 0."""
    wall_geo = np.zeros((len(g.wall_i), 4))
    wall_geo[:, :2] = g.wall_geo[:, :2]
    wall_geo[:, 3] = g.wall_geo[:, 2]
    g3 = Granular3(
        **{
            **g._asdict(),
            "wall_geo": wall_geo,
            "shock_force": np.zeros((len(g.radius), 3)),
            "shock_torque": np.zeros((len(g.radius), 3)),
        }
    )
    y3 = np.zeros((len(y), 9))
    y3[:, 0:2] = y[:, 0:2]
    y3[:, 3:5] = y[:, 3:5]
    y3[:, 8] = y[:, 5]
    return g3, y3


@pytest.mark.parametrize("split", [False, True])
def test_planar_state_in_space_gives_the_planes_forces(split):
    """granular3d.granular_rhs on a planar state equals granular.granular_rhs: the
    accelerations, the angular acceleration along z, nothing out of the plane, and the
    same viscous and friction powers and stored energy (to round-off)."""
    m, g, y = planar_state()
    g3, y3 = lifted(g, y)
    e = np.zeros(0)
    d2, d3 = np.zeros_like(y), np.zeros_like(y3)
    s2 = plane.granular_rhs(0.0, y, e, e, g, m.config, d2, e, e, e, False, e, split)
    s3 = space.granular_rhs(0.0, y3, e, e, g3, m.config._replace(dimension=3), d3, e, e, e, False, e, split)
    scale = np.abs(d2[:, 3:5]).max()
    assert scale > 1.0  # the contacts do push
    np.testing.assert_allclose(d3[:, 3:5], d2[:, 3:5], rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(d3[:, 8], d2[:, 5], rtol=0, atol=1e-12 * np.abs(d2[:, 5]).max())
    assert np.all(d3[:, [2, 5, 6, 7]] == 0.0)
    for name in ("p_visc", "p_fric", "e_pot"):
        assert getattr(s3, name) == pytest.approx(getattr(s2, name), rel=1e-12, abs=1e-300), name
    assert (s3.ovl_i, s3.ovl_j) == (s2.ovl_i, s2.ovl_j)


def test_friction_flow_in_space_relaxes_as_in_the_plane():
    """The split friction in space (the slip speed relaxed along its own direction) on a
    planar state gives the plane's velocities, spins and dissipated energy."""
    m, g, y = planar_state()
    g3, y3 = lifted(g, y)
    w2 = plane.friction_flow(y, 2e-7, g, m.config, True)
    w3 = friction_space.friction_flow(y3, 2e-7, g3, m.config._replace(dimension=3), True)
    assert w2 > 0.0 and w3 == pytest.approx(w2, rel=1e-10)
    np.testing.assert_allclose(y3[:, 3:5], y[:, 3:5], rtol=0, atol=1e-12)
    np.testing.assert_allclose(y3[:, 8], y[:, 5], rtol=0, atol=1e-9)


def test_slip_vector_and_torques_follow_their_definitions():
    """v_s = (v)_t + s x n; friction along -v_s; torque a n x f; in the plane the slip is
    v_t t with t = (-n_y, n_x, 0) and the torque -f a along z (eq. 6)."""
    rng = np.random.default_rng(3)
    n = rng.normal(size=3)
    n /= np.linalg.norm(n)
    v, sv = rng.normal(size=3), rng.normal(size=3)
    want = v - (v @ n) * n + np.cross(sv, n)
    np.testing.assert_allclose(slip_velocity_3d(*v, *sv, *n), want, rtol=1e-13, atol=1e-15)
    f = np.array(friction_vector_3d(2.0, *want))
    np.testing.assert_allclose(f, -2.0 * want / np.linalg.norm(want), rtol=1e-13)
    np.testing.assert_allclose(arm_torque_3d(0.01, *n, *f), 0.01 * np.cross(n, f), rtol=1e-13, atol=1e-18)
    nx, ny = math.cos(0.3), math.sin(0.3)
    vt = slip_velocity_3d(1.0, 2.0, 0.0, 0.0, 0.0, 5.0, nx, ny, 0.0)
    t = np.array([-ny, nx, 0.0])
    vt_plane = (np.array([1.0, 2.0, 0.0]) @ t) + 5.0
    np.testing.assert_allclose(vt, vt_plane * t, rtol=1e-13, atol=1e-15)
    assert friction_vector_3d(1.0, 0.0, 0.0, 0.0) == (0.0, 0.0, 0.0)


def test_kinetic_energies_in_space():
    """1/2 m v^2 per axis and 1/2 I |w|^2 (a sphere's inertia is isotropic)."""
    y = np.array([[0, 0, 0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0]])
    kx, ky, kz, kr = space.kinetic_energies(y, np.array([2.0]), np.array([0.5]))
    assert (kx, ky, kz, kr) == (1.0, 4.0, 9.0, 0.25 * (16 + 25 + 36))


def test_pair_contact_is_the_overlap_and_normal_where_spheres_touch():
    """pair_contact_3d: pair_overlap_3d's overlap exactly and its normal to an ulp where
    the spheres touch; delta <= 0 and a zero normal where they do not (-inf when the
    squared distance already says so); friction_along_slip is friction_vector_3d."""
    rng = np.random.default_rng(11)
    for _ in range(200):
        si, sj = rng.normal(size=3) * 1e-3, rng.normal(size=3) * 1e-3
        ri, rj = rng.uniform(0.5e-3, 1.5e-3, 2)
        got = pair_contact_3d(*si, ri, *sj, rj)
        want = pair_overlap_3d(*si, ri, *sj, rj)
        if want[0] > 0.0:
            assert got[0] == want[0]
            np.testing.assert_allclose(got[1:], want[1:], rtol=0, atol=2 * np.finfo(float).eps)
        else:
            assert got[0] <= 0.0 and got[1:] == (0.0, 0.0, 0.0)
    assert pair_contact_3d(0.0, 0.0, 0.0, 1.0, 3.0, 0.0, 0.0, 1.0)[0] == -math.inf
    assert pair_contact_3d(0.0, 0.0, 0.0, 1.0, 2.0, 0.0, 0.0, 1.0) == (0.0, 0.0, 0.0, 0.0)
    vs = (0.3, -0.4, 1.2)
    assert friction_along_slip(2.0, float(np.linalg.norm(vs)), *vs) == pytest.approx(friction_vector_3d(2.0, *vs))
    assert friction_along_slip(2.0, 0.0, 0.0, 0.0, 0.0) == (0.0, 0.0, 0.0)


def test_friction_is_split_off_in_space_only_where_a_contact_has_friction():
    """model.space: a 3D scenario without friction at any contact runs RK4 unsplit (the
    friction half steps would change nothing); with contact.mu or a pair override it splits."""
    import dataclasses

    from granplate.bench.scaling_space import launched_fcc
    from granplate.setup.scenario import PairCoefficients

    s = launched_fcc((1, 1, 1))
    assert not build_model(s).config.split_friction
    assert build_model(launched_fcc((1, 1, 1), mu=0.099)).config.split_friction
    s = dataclasses.replace(
        s, contact=dataclasses.replace(s.contact, pairs=(PairCoefficients(materials=("steel", "steel"), mu=0.2),))
    )
    assert build_model(s).config.split_friction

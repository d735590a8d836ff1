"""The linear modes of granules on an elastic solid in space (results/modes.py, eq. M4)
against independent solutions: without contact, the solid's own frequencies plus the
granules' rigid modes; a sphere resting on the clamped solid, against a dense eigen-solve of
the whole finite-element model with the sphere's mass on a spring at its contact point (the
face's shape functions there), converging as more modes are kept; and a stiff contact
tending to the solid with the mass attached rigidly."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
from scipy.linalg import eigh

from granplate.model import build_model
from granplate.physics.contact import COEF_A
from granplate.results.modes import body_contacts, linear_modes
from granplate.setup import io as scenario_io
from granplate.solid.boundary import reduced_index
from granplate.solid.fe import mass_matrix, stiffness_matrix, vector_basis
from granplate.solid.surface import boundary_surface, closest_point, patch_weights

TOP = 0.01  # the block's top face [m]
RADIUS = 0.004
#: the spheres' centres (x, y) [m]: off the face's nodes, so that their weights spread over
#: a face, and apart (9.3 mm between them)
CENTRES = ((0.0073, 0.0121), (0.0142, 0.0058))


def scenario(heights, max_frequency: float = 1.5e5) -> str:
    """Steel spheres at the heights [m] (the first at CENTRES[0], ...) over a steel block
    20 x 20 x 10 mm (hex20, 2 x 2 x 1 elements, clamped at the bottom), a point patch."""
    granules = "".join(
        f'[[granules]]\nx = {x}\ny = {y}\nz = {z}\nradius = {RADIUS}\nmaterial = "steel"\n'
        for (x, y), z in zip(CENTRES, heights)
    )
    return f"""
name = "sphere-on-solid"
dimension = 3
{granules}
[plate]
size = [0.02, 0.02, {TOP}]
elements = [2, 2, 1]
material = "steel"
clamped = ["zmin"]
patch_radius = 0.0
max_frequency = {max_frequency}
[load]
kind = "none"
[contact]
overlap_start = 0.01
mu = 0.0
[time]
t_end = 1e-5
"""


def resting(max_frequency: float = 1.5e5, pressed=(2e-6,)):
    """The model of spheres pressed into the top face by `pressed` [m] each."""
    return build_model(scenario_io.loads(scenario([TOP + RADIUS - p for p in pressed], max_frequency)))


def fe_system(model):
    """The solid's dense K, M [N/m, kg] on its free dofs, and C (n_red, ng): the normal (z)
    displacement at each sphere's contact point, the face's shape functions there."""
    solid = model.solid
    mat = solid.material
    k = stiffness_matrix(solid.basis, mat.E, mat.nu)[solid.dofs][:, solid.dofs].toarray()
    m = mass_matrix(solid.basis, mat.rho)[solid.dofs][:, solid.dofs].toarray()
    surface = boundary_surface(vector_basis(solid.mesh, solid.element))
    c = np.zeros((len(solid.dofs), len(model.granular.mass)))
    for i, centre in enumerate(model.initial_state[:, :3]):
        cp = closest_point(surface, centre)
        assert np.allclose(cp.normal, (0.0, 0.0, 1.0))
        dofs, w = patch_weights(surface, cp.face, cp.xi)
        np.add.at(c[:, i], reduced_index(solid.dofs, dofs[:, 2]), w)
    return k, m, c


def residual_at(model, k, c) -> np.ndarray:
    """C^T (K^-1 - Phi diag(1/omega^2) Phi^T) C [m/N]: the truncated modes' static compliance
    between the contact points (a dense solve)."""
    phi_c = model.solid.Phi.T @ c
    return c.T @ np.linalg.solve(k, c) - (phi_c / model.solid.omega[:, None] ** 2).T @ phi_c


def contact_stiffness(model, k, c) -> np.ndarray:
    """(ng,) the Hertz tangents (3/2) A delta^(1/2) [N/m] at the overlaps delta + R A
    delta^(3/2) = delta0 (R: `residual_at`), by Newton from delta0."""
    r = residual_at(model, k, c)
    a = model.body.coef[:, COEF_A]
    delta0 = RADIUS - (model.initial_state[:, 2] - TOP)
    delta = delta0.copy()
    for _ in range(50):
        step = np.linalg.solve(
            np.eye(len(a)) + r * (1.5 * a * np.sqrt(delta))[None, :], delta + r @ (a * delta**1.5) - delta0
        )
        delta -= step
    assert np.max(np.abs(step)) < 1e-15
    return 1.5 * a * np.sqrt(delta)


def spring_modes(k, m, c, ks, masses):
    """(frequencies [Hz], M-orthonormal vectors) of the solid with point masses on springs ks
    at the columns of c (their normal motion only; the masses' unknowns last)."""
    n, ng = c.shape
    kk = np.zeros((n + ng, n + ng))
    kk[:n, :n] = k + (c * ks) @ c.T
    kk[:n, n:] = -c * ks
    kk[n:, :n] = kk[:n, n:].T
    kk[n:, n:] = np.diag(ks)
    mm = np.zeros((n + ng, n + ng))
    mm[:n, :n] = m
    mm[n:, n:] = np.diag(masses)
    lam, v = eigh(kk, mm)
    return np.sqrt(np.maximum(lam, 0.0)) / (2.0 * np.pi), v


def attached_frequencies(k, m, c, mass: float) -> np.ndarray:
    """[Hz] of the solid with the point mass moving with its surface along the normal."""
    return np.sqrt(eigh(k, m + mass * np.outer(c, c), eigvals_only=True)) / (2.0 * np.pi)


def test_without_contact_the_solid_keeps_its_frequencies():
    """Two spheres 1 mm above the solid: the solid's own frequencies (to 1e-8) and the
    spheres' six rigid modes; no contact in touch."""
    model = build_model(scenario_io.loads(scenario([TOP + RADIUS + 1e-3] * 2)))
    modes = linear_modes(model)
    own = np.sort(model.solid.omega / (2.0 * np.pi))
    assert modes.zero_modes == 6 and modes.contacts == 0
    np.testing.assert_allclose(modes.frequencies[6:], own, rtol=1e-8)
    assert modes.plate.shape == (len(own) + 6, len(own))


def test_sphere_on_the_solid_against_the_whole_finite_element_model():
    """The lowest coupled frequencies against the full FE model with the sphere on a spring:
    within 5e-5 with the modes below 150 kHz kept and the residual compliance, closer with
    more modes, exact (1e-9) with all of them."""
    errors = []
    for f_max in (1.5e5, 3e5, 1e8):
        model = resting(f_max)
        k, m, c = fe_system(model)
        ks = contact_stiffness(model, k, c)
        contacts = body_contacts(model, model.initial_state[:, :3])
        np.testing.assert_allclose(contacts.k_s, ks, rtol=1e-9)  # the same overlap as the loop's
        reference, _ = spring_modes(k, m, c, ks, model.granular.mass)
        modes = linear_modes(model)
        assert modes.zero_modes == 2 and modes.contacts == 1  # the sphere slides freely on the face
        got = modes.frequencies[2:6]
        errors.append(float(np.max(np.abs(got / reference[:4] - 1.0))))
    assert errors[0] < 5e-5
    assert errors[1] < 0.2 * errors[0]
    assert errors[2] < 1e-9


def test_two_spheres_coupled_through_the_residual_compliance():
    """Two spheres pressed 2 and 1 um into the solid (the modes below 150 kHz kept): the
    residual compliance between their points against a dense solve (1e-6 of the diagonal),
    and the lowest frequencies and the spheres' share of the lowest modes (sign-invariant)
    against the full FE model with both springs, to 1e-4."""
    model = resting(1.5e5, (2e-6, 1e-6))
    k, m, c = fe_system(model)
    contacts = body_contacts(model, model.initial_state[:, :3])
    r = residual_at(model, k, c)
    np.testing.assert_allclose(contacts.r_n, r, atol=1e-6 * float(np.max(np.diag(r))))
    assert abs(r[0, 1]) > 1e-3 * r[0, 0]  # the two contacts do feel each other through it
    ks = contact_stiffness(model, k, c)
    np.testing.assert_allclose(contacts.k_s, ks, rtol=1e-9)
    reference, v = spring_modes(k, m, c, ks, model.granular.mass)
    modes = linear_modes(model)
    assert modes.zero_modes == 4 and modes.contacts == 2
    np.testing.assert_allclose(modes.frequencies[4:10], reference[:6], rtol=1e-4)
    for j in range(2):  # the two spheres' bounces: their normal amplitudes [kg^-1/2]
        ours, theirs = modes.shapes[4 + j, :, 2], v[-2:, j]
        np.testing.assert_allclose(ours * np.sign(ours @ theirs), theirs, atol=1e-4 * np.max(np.abs(theirs)))


def test_sphere_on_a_free_solid():
    """A sphere pressed 2 um into the block held nowhere (every mode kept, the residual's
    inertia relief negligible): eight zero modes (the block's six rigid modes and the
    sphere's two slides; the bounce of the two bodies on the spring is elastic), and the
    elastic frequencies of the full FE model with the sphere on the Hertz spring to 1e-6."""
    model = build_model(scenario_io.loads(scenario([TOP + RADIUS - 2e-6], 1e8).replace('clamped = ["zmin"]\n', "")))
    k, m, c = fe_system(model)
    ks = 1.5 * model.body.coef[:, COEF_A] * np.sqrt(2e-6)
    np.testing.assert_allclose(body_contacts(model, model.initial_state[:, :3]).k_s, ks, rtol=1e-6)
    reference, _ = spring_modes(k, m, c, ks, model.granular.mass)  # six rigid modes first, at round-off
    modes = linear_modes(model)
    assert modes.zero_modes == 8 and modes.contacts == 1
    np.testing.assert_allclose(modes.frequencies[8:14], reference[6:12], rtol=1e-6)


def test_a_stiff_contact_tends_to_the_mass_attached_rigidly():
    """A contact made 10^2, 10^4, 10^6 times stiffer (Hertz's A): the lowest coupled frequency
    rises towards the solid's with the sphere's mass attached at the point, monotonically, to
    1e-7 (all modes kept)."""
    model = resting(1e8)
    k, m, c = fe_system(model)
    rigid = attached_frequencies(k, m, c[:, 0], float(model.granular.mass[0]))[0]
    gaps = []
    for scale in (1e2, 1e4, 1e6):
        coef = model.body.coef.copy()
        coef[:, COEF_A] *= scale
        stiff = dataclasses.replace(model, body=model.body._replace(coef=coef))
        modes = linear_modes(stiff)
        lowest = modes.frequencies[modes.frequencies > 0.0][0]
        assert lowest < rigid * (1.0 + 1e-9)  # a spring is softer than a rigid link
        gaps.append(1.0 - lowest / rigid)
    assert gaps[0] > gaps[1] > gaps[2]
    assert gaps[2] < 1e-7


def test_cli_json_gives_the_solids_share(tmp_path, capsys):
    """`granplate modes --json` on a 3D scenario with a solid: plate_modes and each mode's
    granule_fraction in [0, 1], the sphere's bounce mostly in the sphere."""
    from granplate.cli import main

    path = tmp_path / "s.toml"
    path.write_text(scenario([TOP + RADIUS - 2e-6]))
    out = tmp_path / "m.json"
    assert main(["modes", str(path), "--json", str(out)]) == 0
    record = json.loads(out.read_text())
    assert record["plate_modes"] > 0 and record["contacts"] == 1
    share = np.array(record["granule_fraction"])
    assert np.all((share > -1e-9) & (share < 1.0 + 1e-9))
    assert share[2] > 0.5  # the lowest elastic mode: the sphere on its contact spring
    assert "coupled to the solid's" in capsys.readouterr().out

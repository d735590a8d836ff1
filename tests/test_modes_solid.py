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
from scipy.optimize import brentq

from granplate.model import build_model
from granplate.physics.contact import COEF_A
from granplate.results.modes import body_contacts, linear_modes
from granplate.setup import io as scenario_io
from granplate.solid.boundary import reduced_index
from granplate.solid.fe import mass_matrix, stiffness_matrix, vector_basis
from granplate.solid.surface import boundary_surface, closest_point, patch_weights

TOP = 0.01  # the block's top face [m]
RADIUS = 0.004
#: the sphere's centre: off the face's nodes, so that its weights spread over a face
CENTRE = (0.0073, 0.0121)


def scenario(z: float, max_frequency: float = 1.5e5, extra: str = "") -> str:
    """A steel sphere at height z [m] over a steel block 20 x 20 x 10 mm (hex20, 2 x 2 x 1
    elements, clamped at the bottom), a point patch."""
    return f"""
name = "sphere-on-solid"
dimension = 3
[[granules]]
x = {CENTRE[0]}
y = {CENTRE[1]}
z = {z}
radius = {RADIUS}
material = "steel"
{extra}
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


def resting(max_frequency: float = 1.5e5):
    """The model of the sphere pressed 2 um into the top face."""
    return build_model(scenario_io.loads(scenario(TOP + RADIUS - 2e-6, max_frequency)))


def fe_system(model):
    """The solid's dense K, M [N/m, kg] on its free dofs, and c (n_red,): the normal (z)
    displacement at the sphere's contact point, the face's shape functions there."""
    solid = model.solid
    mat = solid.material
    k = stiffness_matrix(solid.basis, mat.E, mat.nu)[solid.dofs][:, solid.dofs].toarray()
    m = mass_matrix(solid.basis, mat.rho)[solid.dofs][:, solid.dofs].toarray()
    surface = boundary_surface(vector_basis(solid.mesh, solid.element))
    cp = closest_point(surface, (*CENTRE, model.initial_state[0, 2]))
    assert np.allclose(cp.normal, (0.0, 0.0, 1.0))
    dofs, w = patch_weights(surface, cp.face, cp.xi)
    c = np.zeros(len(solid.dofs))
    np.add.at(c, reduced_index(solid.dofs, dofs[:, 2]), w)
    return k, m, c


def contact_stiffness(model, k, c) -> float:
    """The Hertz tangent (3/2) A delta^(1/2) at the overlap delta + r A delta^(3/2) = delta0,
    r = c^T (K^-1 - Phi diag(1/omega^2) Phi^T) c the truncated modes' static compliance at
    the point (a dense solve)."""
    solid = model.solid
    phi_c = solid.Phi.T @ c
    r = c @ np.linalg.solve(k, c) - np.sum(phi_c**2 / solid.omega**2)
    a = float(model.body.coef[0, COEF_A])
    delta0 = RADIUS - (float(model.initial_state[0, 2]) - TOP)
    delta = brentq(lambda x: x + r * a * x**1.5 - delta0, 0.0, delta0, xtol=1e-18, rtol=1e-15)
    return 1.5 * a * np.sqrt(delta)


def spring_frequencies(k, m, c, ks: float, mass: float) -> np.ndarray:
    """[Hz] of the solid with a point mass on a spring ks at c (its normal motion only)."""
    n = len(c)
    kk = np.zeros((n + 1, n + 1))
    kk[:n, :n] = k + ks * np.outer(c, c)
    kk[:n, n] = kk[n, :n] = -ks * c
    kk[n, n] = ks
    mm = np.zeros((n + 1, n + 1))
    mm[:n, :n] = m
    mm[n, n] = mass
    return np.sqrt(eigh(kk, mm, eigvals_only=True)) / (2.0 * np.pi)


def attached_frequencies(k, m, c, mass: float) -> np.ndarray:
    """[Hz] of the solid with the point mass moving with its surface along the normal."""
    return np.sqrt(eigh(k, m + mass * np.outer(c, c), eigvals_only=True)) / (2.0 * np.pi)


def test_without_contact_the_solid_keeps_its_frequencies():
    """A sphere 1 mm above the solid: the solid's own frequencies (to 1e-8) and the sphere's
    three rigid modes; no contact in touch."""
    model = build_model(scenario_io.loads(scenario(TOP + RADIUS + 1e-3)))
    modes = linear_modes(model)
    own = np.sort(model.solid.omega / (2.0 * np.pi))
    assert modes.zero_modes == 3 and modes.contacts == 0
    np.testing.assert_allclose(modes.frequencies[3:], own, rtol=1e-8)
    assert modes.plate.shape == (len(own) + 3, len(own))


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
        np.testing.assert_allclose(contacts.k_s, [ks], rtol=1e-9)  # the same overlap as the loop's
        reference = spring_frequencies(k, m, c, ks, float(model.granular.mass[0]))
        modes = linear_modes(model)
        assert modes.zero_modes == 2 and modes.contacts == 1  # the sphere slides freely on the face
        got = modes.frequencies[2:6]
        errors.append(float(np.max(np.abs(got / reference[:4] - 1.0))))
    assert errors[0] < 5e-5
    assert errors[1] < 0.2 * errors[0]
    assert errors[2] < 1e-9


def test_a_stiff_contact_tends_to_the_mass_attached_rigidly():
    """A contact made 10^2, 10^4, 10^6 times stiffer (Hertz's A): the lowest coupled frequency
    rises towards the solid's with the sphere's mass attached at the point, monotonically, to
    1e-7 (all modes kept)."""
    model = resting(1e8)
    k, m, c = fe_system(model)
    rigid = attached_frequencies(k, m, c, float(model.granular.mass[0]))[0]
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
    path.write_text(scenario(TOP + RADIUS - 2e-6))
    out = tmp_path / "m.json"
    assert main(["modes", str(path), "--json", str(out)]) == 0
    record = json.loads(out.read_text())
    assert record["plate_modes"] > 0 and record["contacts"] == 1
    share = np.array(record["granule_fraction"])
    assert np.all((share > -1e-9) & (share < 1.0 + 1e-9))
    assert share[2] > 0.5  # the lowest elastic mode: the sphere on its contact spring
    assert "coupled to the solid's" in capsys.readouterr().out

"""Linear modes of granules coupled to the plane's plate (results.modes, docs/model.md section
3.13): the truth is an independent dense eigen-solve of the full finite-element plate
(scikit-fem's own plane-stress elasticity and a consistent mass, K and M assembled here) with
the granule and its Hertz springs added; the closed form of a granule between two rigid
supports as the plate is made very stiff; and the plate's own modes shifted up by a light
granule, the massless limit being the plate with the contact's and wall's springs in series
to ground."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest

import granplate as gp
from granplate.cli import main
from granplate.model.arrays import build_model
from granplate.physics.contact import COEF_A
from granplate.results.modes import linear_modes

#: A 2 x 8 plate at x0 = 0.02 m, one granule on the node at y = 0.05 m, pressed on it by F
#: from the wall "push" on its other side; {materials} may replace the plate's or the granule's.
ONE = """
name = "one-on-plate-modes"
[[granules]]
x = 0.015
y = 0.05
radius = 0.005
material = "{granule}"
[[walls]]
label = "push"
normal = [-1.0, 0.0]
offset = -0.01
[plate]
x0 = 0.02
nx = 2
ny = 8
rigid_layer_width = 0.001
material = "{plate}"
{modes}
[load]
kind = "none"
[precompression]
target = "wall push"
force = 5.0
{materials}
"""
FORCE = 5.0
STEEL = gp.preset("steel-r1").material("steel")


def scenario(modes: str = 'modes = "all"', granule: str = "steel", plate: str = "steel", materials: str = ""):
    return gp.loads(ONE.format(modes=modes, granule=granule, plate=plate, materials=materials))


def springs(model) -> tuple[float, float]:
    """The plate contact's and the wall contact's Hertz stiffness (3/2) A^(2/3) F^(1/3) [N/m]
    at the static state, where each carries F; A of a sphere on a rigid flat, (4/3) E/(1 - nu^2)
    sqrt(R) (docs/model.md sections 3.3, 3.4)."""
    g = model.granular
    a = 4.0 / 3.0 * STEEL.E / (1.0 - STEEL.nu**2) * math.sqrt(0.005)
    assert g.pc_coef[0, COEF_A] == pytest.approx(a, rel=1e-12)
    assert g.wall_coef[0, COEF_A] == pytest.approx(a, rel=1e-12)
    k = 1.5 * a ** (2.0 / 3.0) * FORCE ** (1.0 / 3.0)
    return k, k


def fe_spectrum(plate, e: float, mass: float, k_plate: float, k_wall: float, count: int) -> np.ndarray:
    """The lowest `count` frequencies [Hz] of the full finite-element plate (Q8 plane stress,
    top and bottom clamped, E = e, steel's nu and rho) with a granule of `mass` tied to its
    left-edge node at y = 0.05 m by k_plate and to the ground by k_wall (mass 0: the two
    springs in series to ground), by scipy's dense generalised `eigh`."""
    from scipy.linalg import eigh
    from skfem import BilinearForm, Basis, ElementQuadS2, ElementVector, MeshQuad, asm
    from skfem.helpers import dot
    from skfem.models.elasticity import lame_parameters, linear_elasticity

    mesh = MeshQuad.init_tensor(
        np.linspace(plate.x0, plate.x0 + plate.width, plate.nx + 1), np.linspace(0.0, plate.height, plate.ny + 1)
    )
    basis = Basis(mesh, ElementVector(ElementQuadS2()), intorder=4)
    lam, mu = lame_parameters(e, STEEL.nu)
    lam = 2.0 * lam * mu / (lam + 2.0 * mu)  # plane stress
    K = (asm(linear_elasticity(lam, mu), basis) * plate.thickness).toarray()
    rho_t = STEEL.rho * plate.thickness
    M = asm(BilinearForm(lambda u, v, w: rho_t * dot(u, v)), basis).toarray()
    xy = basis.doflocs
    free = np.flatnonzero((np.abs(xy[1]) > 1e-12) & (np.abs(xy[1] - plate.height) > 1e-12))
    vertex = int(np.flatnonzero((np.abs(mesh.p[0] - plate.x0) < 1e-12) & (np.abs(mesh.p[1] - 0.05) < 1e-12))[0])
    c = int(np.flatnonzero(free == basis.nodal_dofs[0, vertex])[0])
    K, M = K[np.ix_(free, free)], M[np.ix_(free, free)]
    n = len(free)
    if mass == 0.0:
        K[c, c] += k_plate * k_wall / (k_plate + k_wall)
    else:
        K = np.pad(K, ((0, 1), (0, 1)))
        M = np.pad(M, ((0, 1), (0, 1)))
        K[c, c] += k_plate
        K[n, n] = k_plate + k_wall
        K[c, n] = K[n, c] = -k_plate
        M[n, n] = mass
    lam_ = eigh(K, M, eigvals_only=True, subset_by_index=[0, count - 1])
    return np.sqrt(lam_) / (2.0 * math.pi)


def test_a_granule_on_the_plate_against_the_full_finite_element_model():
    """Every mode kept: the lowest coupled frequencies equal the independent dense solve of the
    full FE plate with the granule and its springs (1e-9); the truncated basis (200 kHz, its
    residual compliance in series with the contact spring) within 2e-4 below 60 kHz, where
    the same basis without its residual compliance is off by more than 1e-2. The
    coupled spectrum is not the granule's alone (the steel plate is not rigid), and two calls
    give bitwise the same modes."""
    s = scenario()
    model = build_model(s)
    kp, kw = springs(model)
    mass = float(model.granular.mass[0])
    md = linear_modes(model)
    assert md.contacts == 2 and md.zero_modes == 1  # the granule's y has no stiffness
    f = md.frequencies[md.frequencies > 0]
    truth = fe_spectrum(s.plate, STEEL.E, mass, kp, kw, 8)
    np.testing.assert_allclose(f[:8], truth, rtol=1e-9)
    rigid = math.sqrt((kp + kw) / mass) / (2 * math.pi)
    assert abs(f[0] / rigid - 1.0) > 0.05  # the plate's compliance matters here
    again = linear_modes(build_model(s))
    assert np.array_equal(again.frequencies, md.frequencies) and np.array_equal(again.plate, md.plate)
    # M-orthonormal: the granule's kinetic share plus the plate's is 1
    np.testing.assert_allclose(
        mass * md.shapes[:, 0, 0] ** 2 + mass * md.shapes[:, 0, 1] ** 2 + np.sum(md.plate**2, 1), 1.0, rtol=1e-9
    )
    truncated = build_model(scenario('modes = "truncated"\nmax_frequency = 2e5'))
    low = truth < 6e4
    ft = linear_modes(truncated).frequencies
    np.testing.assert_allclose(ft[ft > 0][: int(low.sum())], truth[low], rtol=2e-4)
    bare = dataclasses.replace(truncated, plate_arrays=truncated.plate_arrays._replace(resid=np.zeros((0, 0))))
    fb = linear_modes(bare).frequencies
    assert np.max(np.abs(fb[fb > 0][: int(low.sum())] / truth[low] - 1.0)) > 1e-2


def test_a_stiff_plate_leaves_the_granule_between_rigid_supports():
    """The plate's stiffness x 50 (E, the largest the scenario allows) and x 1e4 (thickness x 200
    too): the lowest coupled frequency tends to the granule's between a wall and a rigid flat,
    sqrt((k_p + k_w) / m) / (2 pi): 3.5% below it, then within 1e-3 (the steel plate's is half
    of it)."""
    stiff = f"[materials.stiff]\nE = {STEEL.E * 50}\nnu = {STEEL.nu}\nrho = {STEEL.rho}\n"
    errors = []
    for thickness in (0.001, 0.2):
        model = build_model(gp.with_changes(scenario(plate="stiff", materials=stiff), {"plate.thickness": thickness}))
        kp, kw = springs(model)
        f = linear_modes(model).frequencies
        rigid = math.sqrt((kp + kw) / float(model.granular.mass[0])) / (2 * math.pi)
        errors.append(abs(f[f > 0][0] / rigid - 1.0))
    assert 0.02 < errors[0] < 0.05 and errors[1] < 1e-3


def test_a_light_granule_shifts_the_plates_own_modes_up():
    """A granule 1000 times lighter than steel: the coupled spectrum holds the plate's own modes,
    each at or above the bare plate's (the contact adds stiffness, hardly any mass), and equal
    within 1e-3 to the FE plate with the contact's and the wall's springs in series to ground;
    the granule's own mode lies far above them. The bare plate's frequencies are the FE solve's."""
    light = f"[materials.light]\nE = {STEEL.E}\nnu = {STEEL.nu}\nrho = {STEEL.rho * 1e-3}\n"
    s = scenario(granule="light", materials=light)
    model = build_model(s)
    kp, kw = springs(model)
    f = linear_modes(model).frequencies
    f = f[f > 0]
    bare = np.sqrt(np.asarray(model.plate_arrays.omega2[:6])) / (2 * math.pi)
    np.testing.assert_allclose(bare, fe_spectrum(s.plate, STEEL.E, 0.0, 0.0, 1.0, 6), rtol=1e-7)
    grounded = fe_spectrum(s.plate, STEEL.E, 0.0, kp, kw, 6)
    np.testing.assert_allclose(f[:6], grounded, rtol=1e-3)
    assert np.all(f[:6] >= bare * (1 - 1e-9)) and f[0] > 1.2 * bare[0]
    rigid = math.sqrt((kp + kw) / float(model.granular.mass[0])) / (2 * math.pi)
    assert f.max() > rigid


def test_modes_command_writes_the_plates_share(tmp_path):
    """`granplate modes --json` with the plate: the frequencies as `linear_modes`, the plate's
    modal count, and each mode's granule share in [0, 1] summing over the modes to the
    granules' unknowns (2: x and y of one granule, an M-orthonormal basis)."""
    path = tmp_path / "one.toml"
    path.write_text(ONE.format(modes='modes = "all"', granule="steel", plate="steel", materials=""))
    out = tmp_path / "modes.json"
    assert main(["modes", str(path), "--json", str(out), "--figure", str(tmp_path / "m.png")]) == 0
    got = json.loads(out.read_text())
    md = linear_modes(build_model(scenario()))
    np.testing.assert_allclose(got["frequencies"], md.frequencies, rtol=1e-12)
    assert got["plate_modes"] == len(build_model(scenario()).plate_arrays.omega2)
    share = np.asarray(got["granule_fraction"])
    assert np.all((share > -1e-9) & (share < 1 + 1e-9)) and share.sum() == pytest.approx(2.0, rel=1e-9)

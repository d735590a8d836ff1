"""Gravity with the plane's plate (granplate.model.plate_weight): the truth is statics and
eq. (11). The plate's sag under its own weight is an independent scikit-fem static solve
(its own plane-stress elasticity and body-force forms) and, to the beam's accuracy, the
clamped-clamped Timoshenko beam; a bare plate starts at rest in it and stays there; a sphere
falling onto the plate bounces with eq. (11) holding at every output step; a sphere pressed
onto the plate by a wall and its weight sits where statics puts it on the sagged face; a 3D
plate with gravity is refused naming gravity.g."""

from __future__ import annotations

import math

import numpy as np
import pytest

import granplate as gp
from granplate.errors import YieldWarning
from granplate.model.arrays import build_model
from granplate.model.plate_weight import sag_at_contacts, weight_forces, weight_sag
from granplate.physics.contact import COEF_A

#: the spheres pressed onto the plate pass Hertz's yield onset; the elastic law is the truth here
pytestmark = pytest.mark.filterwarnings("ignore", category=YieldWarning)

#: One steel sphere at a face node (y = 0.05 m) of a 2 x 8 plate at x0 = 0.02 m, gravity
#: along +x (onto the plate: its face normal, the plate bends under its own weight).
ONE = """
name = "one-on-plate-under-gravity"
[[granules]]
x = {x}
y = 0.05
radius = 0.005
material = "steel"
[plate]
x0 = 0.02
nx = 2
ny = 8
rigid_layer_width = 0.001
[load]
kind = "none"
[gravity]
g = [{g}, 0.0]
[time]
t_end = {t_end}
output_interval = {out}
{extra}
"""


def skfem_sag(plate, rho: float, g: tuple[float, float], unit_at: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """An independent static solve K u = f with scikit-fem's plane-stress elasticity form on the
    plate's Q8 mesh, top and bottom clamped: f the body force rho t g (or, with unit_at, a unit
    x force at the left-edge node at that height). Returns (node coordinates (2, n), u (2, n))."""
    from scipy.sparse.linalg import spsolve
    from skfem import Basis, ElementQuadS2, ElementVector, LinearForm, MeshQuad, asm
    from skfem.models.elasticity import lame_parameters, linear_elasticity

    mesh = MeshQuad.init_tensor(
        np.linspace(plate.x0, plate.x0 + plate.width, plate.nx + 1), np.linspace(0.0, plate.height, plate.ny + 1)
    )
    basis = Basis(mesh, ElementVector(ElementQuadS2()), intorder=4)
    steel = gp.preset("steel-r1").material("steel")
    lam, mu = lame_parameters(steel.E, steel.nu)
    lam = 2.0 * lam * mu / (lam + 2.0 * mu)  # plane stress
    K = asm(linear_elasticity(lam, mu), basis).tocsr() * plate.thickness

    @LinearForm
    def weight(v, w):
        return rho * plate.thickness * (g[0] * v[0] + g[1] * v[1])

    f = asm(weight, basis)
    xy = basis.doflocs
    if unit_at is not None:
        f = np.zeros(K.shape[0])
        f[np.flatnonzero((np.abs(xy[0] - plate.x0) < 1e-12) & (np.abs(xy[1] - unit_at) < 1e-12))[0]] = 1.0
    clamped = np.flatnonzero((np.abs(xy[1]) < 1e-12) | (np.abs(xy[1] - plate.height) < 1e-12))
    free = np.setdiff1d(np.arange(K.shape[0]), clamped)
    u = np.zeros(K.shape[0])
    u[free] = spsolve(K[free][:, free].tocsc(), f[free])
    return xy, u


def at_node(xy: np.ndarray, u: np.ndarray, x: float, y: float, comp: int = 0) -> float:
    """u's component comp at the node (x, y)."""
    hit = (np.abs(xy[0] - x) < 1e-12) & (np.abs(xy[1] - y) < 1e-12)
    return float(u[np.flatnonzero(hit)[comp]])


BARE = """
name = "bare-plate-under-gravity"
[plate]
x0 = 0.02
nx = 2
ny = 8
{modes}
[load]
kind = "none"
[gravity]
g = [{gx}, {gy}]
[time]
t_end = 2e-5
output_interval = 2e-6
"""


def bare(g: tuple[float, float], modes: str = "") -> gp.Scenario:
    """The 2 x 8 plate alone under gravity g, no load."""
    return gp.loads(BARE.format(modes=modes, gx=g[0], gy=g[1]))


@pytest.mark.parametrize("g", [(9.81, 0.0), (-3.0, 9.81)])
def test_the_plates_sag_is_the_independent_static_solve(g):
    """The sag under the plate's own weight (any direction of g: the plane-stress plate carries a
    body force along its length too) equals scikit-fem's own static solve at every left-edge
    node (1e-9 of the largest), and its weight's resultant is rho t A g."""
    s = bare(g)
    plate = build_model(s).plate
    rho = s.material(s.plate.material).rho
    full = (plate.T @ weight_sag(plate, np.asarray(g))).reshape(-1, 2)
    xy, u = skfem_sag(s.plate, rho, g)
    ref = np.array([[at_node(xy, u, x, y, c) for c in range(2)] for x, y in plate.node_xy])
    np.testing.assert_allclose(full, ref, rtol=0.0, atol=1e-9 * np.max(np.abs(u)))
    # the consistent nodal forces of the weight (before the clamps take theirs) sum to rho t A g
    f_full = plate.mass_matrix() @ np.tile(np.asarray(g, float), len(plate.node_xy))
    area = s.plate.width * s.plate.height * s.plate.thickness
    np.testing.assert_allclose([f_full[0::2].sum(), f_full[1::2].sum()], rho * area * np.asarray(g), rtol=1e-12)


def test_the_sag_across_the_plate_is_a_clamped_timoshenko_beams():
    """Gravity across the plate (along x): its centre line sags as a clamped-clamped beam of
    depth w under q = rho t w g, q L^4 / (384 E I) + q L^2 / (8 kappa G A), to the 2D continuum's
    departure from beam theory at L / w = 10 (5 %)."""
    g = 9.81
    s = bare((g, 0.0))
    plate = build_model(s).plate
    m = s.material(s.plate.material)
    w, t, L = s.plate.width, s.plate.thickness, s.plate.height
    q = m.rho * t * w * g
    bending = q * L**4 / (384.0 * m.E * t * w**3 / 12.0)
    shear = q * L**2 / (8.0 * (5.0 / 6.0) * m.E / (2.0 * (1.0 + m.nu)) * t * w)
    full = (plate.T @ weight_sag(plate, np.array([g, 0.0]))).reshape(-1, 2)
    mid = np.abs(plate.node_xy[:, 1] - 0.5 * L) < 1e-12
    centre = float(np.mean(full[mid, 0]))
    assert centre == pytest.approx(bending + shear, rel=0.05)


@pytest.mark.parametrize("modes", ['modes = "all"', 'modes = "truncated"\nmax_frequency = 2e5'])
def test_a_bare_plate_under_its_weight_stays_at_rest_in_its_sag(modes):
    """No contact, no load: the sag is the modes' static response Omega^-2 Phi^T f_g (every mode
    kept: exactly the modal equations' rest state under the constant modal force), the run keeps
    the plate at rest (its energy about the sag, E_plate, 0) and eq. (11) holds to round-off."""
    g = np.array([9.81, 0.0])
    s = bare(tuple(g), modes)
    model = build_model(s)
    plate = model.plate
    x_s = weight_sag(plate, g)
    f = weight_forces(plate, g)
    if "all" in modes:
        np.testing.assert_allclose(
            plate.Phi @ ((plate.Phi.T @ f) / plate.omega**2), x_s, atol=1e-9 * np.max(np.abs(x_s))
        )
    ds = gp.simulate(s, progress=False)
    assert np.max(np.abs(ds["E_plate"].values)) == 0.0
    assert np.max(np.abs(ds["energy_residual"].values)) < 1e-12


def test_a_sphere_falls_onto_the_plate_and_bounces_with_eq_11_at_every_step():
    """A steel sphere 2 um off the plate, gravity 100 m/s^2 onto it: it falls freely (its speed
    g t until it touches), bounces off the sagged plate (its velocity reverses), and eq. (11)
    with gravity's work holds at every output step to solver.energy_tol."""
    gx = 100.0
    x0, r = 0.02, 0.005
    s = gp.loads(ONE.format(x=x0 - r - 2e-6, g=gx, t_end=6e-4, out=2e-6, extra=""))
    model = build_model(s)
    assert model.granular.pc_x[0] == pytest.approx(x0 + sag_at_contacts(model.plate, np.array([gx, 0.0]))[0])
    ds = gp.simulate(s, progress=False)
    t = ds["time"].values
    vx = ds["vx"].values[:, 0]
    free = t < math.sqrt(2 * 2e-6 / gx) * 0.95
    np.testing.assert_allclose(vx[free], gx * t[free], rtol=1e-9, atol=1e-15)
    assert np.max(vx) > 0.0 and np.min(vx) < -0.5 * np.max(vx)  # it came back off the plate
    assert float(ds["E_gravity"].values[-1]) > 0.0
    assert np.max(np.abs(ds["energy_residual"].values)) < s.solver.energy_tol


def test_a_sphere_pressed_onto_the_sagged_plate_sits_where_statics_puts_it():
    """A wall pushes the sphere onto the plate with F = 5 N, its weight m g (g = 1000 m/s^2) adds
    to it: the plate contact carries F + m g, the plate's contact node sits at the independent
    solve's sag plus its compliance x (F + m g), the sphere at the Hertz overlap ((F + m g) / A)^(2/3)
    from there, and the run stays at rest with eq. (11) at round-off."""
    gx, force = 1000.0, 5.0
    extra = '[[walls]]\nlabel = "push"\nnormal = [-1.0, 0.0]\noffset = -0.01\n[precompression]\ntarget = "wall push"\nforce = 5.0'
    s = gp.loads(ONE.format(x=0.015, g=gx, t_end=4e-6, out=1e-6, extra=extra))
    model = build_model(s)
    steel = s.material("steel")
    m = steel.rho * 4.0 / 3.0 * math.pi * 0.005**3
    load = force + m * gx
    xy, sag = skfem_sag(s.plate, steel.rho, (gx, 0.0))
    _, unit = skfem_sag(s.plate, steel.rho, (gx, 0.0), unit_at=0.05)
    face = s.plate.x0 + at_node(xy, sag, s.plate.x0, 0.05) + at_node(xy, unit, s.plate.x0, 0.05) * load
    a = model.granular.pc_coef[0, COEF_A]
    x = model.initial_state[0, 0]
    assert abs(at_node(xy, sag, s.plate.x0, 0.05)) > 0.1 * (load / a) ** (2.0 / 3.0)  # the sag matters here
    assert face - (x + 0.005) == pytest.approx(-((load / a) ** (2.0 / 3.0)), rel=1e-5)
    ds = gp.simulate(s, progress=False)
    assert float(ds["contact_normal_force"].values[0, 0]) == pytest.approx(load, rel=1e-6)
    assert np.max(np.abs(ds["x"].values - ds["x"].values[0])) < 1e-12
    assert np.max(np.abs(ds["energy_residual"].values)) < 1e-9


def test_gravity_with_a_3d_plate_is_valid():
    """Space's elastic solid carries its weight (model.body_weight; tests/test_body_gravity.py):
    gravity with a 3D [plate] passes validation."""
    from pathlib import Path

    from granplate.setup.validate import validate

    text = (Path(__file__).resolve().parents[1] / "docs" / "examples" / "3d-fcc-on-plate.toml").read_text()
    validate(gp.loads(text + "\n[gravity]\ng = [-9.81, 0.0, 0.0]\n"))

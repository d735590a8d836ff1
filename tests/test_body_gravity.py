"""Space's elastic solid under its own weight and in the static state of [precompression]
(model.body_weight, model.body_static): its sag against scikit-fem's static solution, the
run starting at rest in the sag, eq. (11) with the solid's weight's work, and a sphere
pressed on the solid resting with the force the statics give it."""

from __future__ import annotations

import numpy as np
import pytest

import granplate as gp
from granplate.model import build_model
from granplate.model.inputs import new_body_state
from granplate.solver import body as B

G = 400.0  # [m/s^2]: a 2 mm steel sphere's weight (0.1 N) comparable with the precompression

SOLID = """
name = "heavy"
dimension = 3
[[granules]]
label = "ball"
x = 0.01
y = 0.01
z = {z}
vz = {vz}
radius = 0.002
material = "steel"
[plate]
size = [0.02, 0.02, 0.01]
elements = [3, 3, 2]
material = "steel"
clamped = ["zmin"]
patch_radius = 0.0
max_frequency = {fmax}
{more}
[load]
kind = "none"
[gravity]
g = [0.0, 0.0, {g}]
[time]
t_end = {t_end}
dt_max = 2e-8
output_interval = 2e-7
field_interval = 2e-6
[solver]
scheme = "{scheme}"
"""

BEAM = """
name = "beam"
dimension = 3
[[granules]]
label = "ball"
x = 0.02
y = 0.005
z = 0.05
radius = 0.001
material = "steel"
[plate]
size = [0.04, 0.01, 0.004]
elements = [4, 1, 1]
material = "steel"
clamped = ["xmin", "xmax"]
max_frequency = {fmax}
[load]
kind = "none"
[gravity]
g = [0.0, 0.0, -9.81]
[time]
t_end = 1e-6
dt_max = 1e-8
output_interval = 1e-7
[solver]
scheme = "verlet"
"""


def fe_centre_sag(solid, g: float, centre: np.ndarray) -> float:
    """The z displacement [m] at `centre` of the solid clamped at x = 0 and x = L under rho g
    along z, from scikit-fem's own assembly (linear_elasticity, a body-force LinearForm) and
    one direct solve of K u = f on the same mesh and element."""
    import skfem
    from skfem.helpers import dot
    from skfem.models.elasticity import lame_parameters, linear_elasticity

    mesh = solid.mesh
    basis = skfem.Basis(mesh, skfem.ElementVector(skfem.ElementHexS2()), intorder=4)
    mat = solid.material
    K = skfem.asm(linear_elasticity(*lame_parameters(mat.E, mat.nu)), basis)
    gv = np.array([0.0, 0.0, g])

    @skfem.LinearForm
    def weight(v, w):
        return mat.rho * dot(np.broadcast_to(gv[:, None, None], v.shape), v)

    f = skfem.asm(weight, basis)
    x = mesh.p[0]
    ends = mesh.facets_satisfying(lambda p: np.isclose(p[0], x.min()) | np.isclose(p[0], x.max()))
    u = skfem.solve(*skfem.condense(K, f, D=basis.get_dofs(ends).all()))
    probe = basis.probes(centre[:, None])
    return float((probe @ u).reshape(3, -1)[2, 0]) if probe.shape[0] == 3 else float(probe[2] @ u)


def granplate_centre(solid, sag: np.ndarray, centre: np.ndarray) -> float:
    """The z displacement [m] at the solid's node at `centre` of a reduced displacement sag."""
    node = int(np.argmin(np.linalg.norm(solid.nodes - centre, axis=1)))
    assert np.linalg.norm(solid.nodes[node] - centre) < 1e-12
    row = int(np.flatnonzero(solid.dofs == 3 * node + 2)[0])
    return float(sag[row])


def test_the_sag_converges_to_the_finite_element_static_solution():
    """A beam clamped at both ends under its own weight: the top's centre's sag from the modes,
    sum phi_k f_k / omega_k^2, converges to scikit-fem's direct solve of K u = f as modes are
    added, and with the residual's static share it is that solution."""
    from granplate.model.body_weight import modal_sag, residual_sag

    g = np.array([0.0, 0.0, -9.81])
    errors = []
    truth = None
    for fmax in (2e4, 2e5):
        m = build_model(gp.loads(BEAM.format(fmax=fmax)))
        solid = m.solid
        lo, hi = solid.nodes.min(axis=0), solid.nodes.max(axis=0)
        centre = np.array([0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), hi[2]])  # the top's mid-edge node
        if truth is None:
            truth = fe_centre_sag(solid, -9.81, centre)
        q = modal_sag(solid, g)
        assert np.allclose(m.plate_q0, q) and np.allclose(m.body.weight, q * solid.omega**2)
        modal = granplate_centre(solid, solid.Phi @ q, centre)
        errors.append(abs(modal - truth) / abs(truth))
        full = granplate_centre(solid, solid.Phi @ q + residual_sag(solid, g), centre)
        assert full == pytest.approx(truth, rel=1e-8)
    assert truth < 0.0
    assert errors[1] < 0.1 * errors[0] and errors[1] < 1e-3, errors


def test_a_free_solid_under_gravity_is_refused_by_name():
    """A solid nothing holds against its weight (no clamped face) has no static sag: refused,
    naming gravity.g."""
    from granplate.errors import ScenarioError

    text = SOLID.format(vz=0.0, z=0.02, fmax=1.5e5, more="", g=-G, t_end=2e-6, scheme="verlet").replace(
        'clamped = ["zmin"]\n', ""
    )
    with pytest.raises(ScenarioError, match="weight") as e:
        build_model(gp.loads(text))
    assert e.value.field == "gravity.g"


@pytest.mark.parametrize("scheme", ["verlet", "implicit"])
def test_the_solid_rests_in_its_sag_and_eq_11_holds_with_a_sphere_dropped_on_it(scheme):
    """Without a contact the solid starts at rest in its sag and stays there to round-off (its
    modes turn exactly about it); a sphere striking it under gravity: eq. (11) holds at every
    step with the weight's work on the solid and the sphere booked as gravity's. Both schemes
    that drive the solid."""
    s = gp.loads(SOLID.format(vz=0.0, z=0.02, fmax=1.5e5, more="", g=-G, t_end=4e-6, scheme=scheme))
    m = build_model(s)
    ds = gp.simulate(s, progress=False)
    q = ds["body_q"].values
    assert np.max(np.abs(ds["energy_residual"].values)) < 1e-10
    assert np.max(np.abs(q - m.plate_q0[None, :])) < 1e-9 * np.max(np.abs(m.plate_q0))
    s = gp.loads(SOLID.format(vz=-0.2, z=0.0120005, fmax=1.5e5, more="", g=-G, t_end=1.5e-5, scheme=scheme))
    ds = gp.simulate(s, progress=False)
    assert float(np.max(ds["E_contact"].values)) > 0.0
    assert np.max(np.abs(ds["energy_residual"].values)) < 1e-5


@pytest.mark.parametrize(
    "residual, patch, scheme", [(True, 0.0, "verlet"), (False, 0.006, "verlet"), (True, 0.0, "implicit")]
)
def test_a_sphere_pressed_on_the_heavy_solid_rests_with_the_static_force(residual, patch, scheme):
    """A sphere pressed on the solid's top face by a wall with F under gravity
    ([precompression]): at t = 0 the solid pushes back with F + m g, and the run from that
    state stays at rest (the sphere's speed a round-off's); with the residual compliance and a
    point patch, and with the modes alone and a disc patch; under either scheme that drives
    the solid."""
    force = 0.1
    wall = (
        f"residual = {'true' if residual else 'false'}\n"
        '[[walls]]\nlabel = "top"\nnormal = [0.0, 0.0, 1.0]\noffset = 0.014\n'
        f'[precompression]\ntarget = "wall top"\nforce = {force}\ntolerance = 1e-10\n'
    )
    text = SOLID.format(vz=0.0, z=0.012, fmax=1.5e5, more=wall, g=-G, t_end=2e-6, scheme=scheme)
    s = gp.loads(text.replace("patch_radius = 0.0", f"patch_radius = {patch}"))
    m = build_model(s)
    mass = float(m.granular.mass[0])
    y = np.ascontiguousarray(m.initial_state.copy())
    acc = np.zeros_like(y)
    b = new_body_state(m.body)
    B.contact_forces(
        y,
        m.plate_q0,
        np.zeros_like(m.plate_q0),
        b,
        0,
        m.granular.radius,
        m.granular.mass,
        False,
        acc,
        acc.copy(),
        False,
    )
    assert acc[0, 5] == pytest.approx(force + mass * G, rel=1e-6)
    assert abs(acc[0, 3]) + abs(acc[0, 4]) < 1e-9 * acc[0, 5]
    ds = gp.simulate(s, progress=False)
    assert np.abs(ds["vz"].values).max() < 1e-8  # against 1e-2 m/s falling from the overlap's height
    assert np.max(np.abs(ds["z"].values - ds["z"].values[0])) < 1e-14
    q = ds["body_q"].values
    assert np.max(np.abs(q - m.plate_q0[None, :])) < 1e-5 * np.max(np.abs(m.plate_q0))
    assert np.max(np.abs(ds["energy_residual"].values)) < 1e-9

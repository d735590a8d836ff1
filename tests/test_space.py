"""Runs in space (dimension = 3, docs/model.md section 3.7) against truth: an oblique
impact with out-of-plane spins and a wall against the independent scipy integrator of
the 3D laws, eq. (11) at every step, the elastic-plastic law's restitution (Thornton),
and the guards of the plane in space."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import granplate as gp
from granplate.errors import SimulationError, YieldWarning
from granplate.setup.materials import effective_modulus
from granplate.verification.plastic import thornton_restitution, thornton_yield_velocity
from granplate.verification.space import reference_motion_3d

STATE = ("x", "y", "z", "vx", "vy", "vz", "omega_x", "omega_y", "omega_z")


def oblique(scheme: str = "paper", t_end: float = 8e-4, law: str = "hertz", extra: str = "") -> gp.Scenario:
    """Sphere a (R = 1 cm, 2 m/s, spinning about all three axes) hits sphere b off-centre
    in x, y and z, and then the wall y = -0.0103 m below it: friction 0.3, damping 0.05."""
    return gp.loads(f"""
dimension = 3
name = "oblique-3d"
[[granules]]
label = "a"
x = 0.0
y = 0.0
z = 0.0
radius = 0.01
material = "steel"
vx = 2.0
vy = -0.5
vz = -0.15
omega = [10.0, -20.0, 30.0]
[[granules]]
label = "b"
x = 0.0199
y = 0.004
z = -0.003
radius = 0.01
material = "steel"
vx = -1.0
omega = [0.0, 5.0, 0.0]
[[walls]]
label = "floor"
normal = [0.0, -1.0, 0.0]
offset = 0.0103
material = "steel"
[load]
kind = "none"
[contact]
mu = 0.3
alpha_n = 0.05
normal_law = "{law}"
pairs = []
{extra}
[time]
t_end = {t_end}
dt_initial = 1e-8
dt_max = 2e-8
output_interval = 1e-5
field_interval = 1e-5
[solver]
scheme = "{scheme}"
error_tol = 1e-5
""")


def quiet(s):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", YieldWarning)
        return gp.simulate(s, progress=False)


@pytest.fixture(scope="module")
def reference():
    s = oblique()
    times = np.arange(0, 81) * 1e-5
    return reference_motion_3d(s, times)


@pytest.mark.parametrize("scheme", ["paper", "implicit"])
def test_oblique_impact_with_spins_matches_the_independent_integrator(scheme, reference):
    """Both spheres' centres, velocities and spin vectors follow the scipy integrator of
    the 3D laws within 2e-5 of the launch speed (spins: of the largest spin; the implicit
    scheme at solver.error_tol = 1e-5), through a pair contact and a wall contact; eq. (11)
    holds at every step."""
    ds = quiet(oblique(scheme))
    assert ds.sizes["time"] == reference.shape[0]
    touched = set(str(p) for p in ds.material_pair.values)
    assert touched == {"steel-steel", "steel-wall"}  # both contacts happened
    for c, name in enumerate(STATE):
        got, want = ds[name].values, reference[:, c, :]
        scale = 2.0 if c < 6 else 30.0
        tol = (2e-5 * scale * 1e-3) if c < 3 else 2e-5 * scale  # positions: over ~1 ms
        np.testing.assert_allclose(got, want, rtol=0, atol=tol, err_msg=name)
    assert float(np.max(np.abs(ds.energy_residual_max))) < 1e-6
    assert float(ds.D_friction[-1]) > 0.0 and float(ds.D_viscous[-1]) > 0.0
    assert set(ds.data_vars) >= {"KE_depth", "E_granular"} and "theta" not in ds


def test_plastic_wall_impact_in_space_rebounds_as_thornton():
    """The elastic-plastic law in space: a sphere hitting a wall along an oblique normal
    (n = (1, 1, 1)/sqrt 3) at 10 v_y rebounds with Thornton's restitution (P12)."""
    steel = gp.preset("steel-r1").material("steel")
    e_star = effective_modulus(steel, None)
    m = 4 / 3 * math.pi * 0.01**3 * steel.rho
    v = 10.0 * thornton_yield_velocity(e_star, 0.01, m, 1.6 * steel.Y)
    n = np.ones(3) / math.sqrt(3.0)
    s = gp.loads(f"""
dimension = 3
[[granules]]
label = "a"
x = 0.0
y = 0.0
z = 0.0
radius = 0.01
material = "steel"
vx = {v * n[0]}
vy = {v * n[1]}
vz = {v * n[2]}
[[walls]]
normal = [1.0, 1.0, 1.0]
offset = 0.01
material = "steel"
[load]
kind = "none"
[contact]
alpha_n = 0.0
mu = 0.0
normal_law = "thornton"
pairs = []
[time]
t_end = 2e-4
dt_initial = 2e-8
dt_max = 2e-8
output_interval = 1e-6
field_interval = 1e-6
""")
    ds = quiet(s)
    vout = np.array([ds[c].values[-1, 0] for c in ("vx", "vy", "vz")])
    assert -vout @ n / v == pytest.approx(thornton_restitution(10.0), rel=1e-3)
    np.testing.assert_allclose(np.cross(vout, n), 0.0, atol=1e-9 * v)  # straight back
    assert float(ds.D_plastic[-1]) == pytest.approx(0.5 * m * (v * v - vout @ vout), rel=1e-6)


def test_overlap_beyond_the_stop_in_space_names_the_granules():
    """Two spheres closing at 500 m/s reach contact.overlap_stop: the run stops naming both
    granules and keeps what it computed."""
    s = gp.with_changes(
        oblique(t_end=2e-5),
        {
            "granules[0].vx": 500.0,
            "granules[1].vx": 0.0,
            "granules[1].x": 0.0202,
            "granules[1].y": 0.0,
            "granules[1].z": 0.0,
        },
    )
    with pytest.raises(SimulationError, match="granule 'a'.*granule 'b'.*overlap_stop") as err:
        quiet(s)
    assert err.value.result.sizes["time"] >= 1

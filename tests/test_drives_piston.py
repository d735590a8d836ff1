"""Force-driven walls (pistons, docs/model.md section 3.11, eq. D1) against closed forms: a
piston of mass M pushed by a constant force P onto a held sphere is a mass on a Hertz
spring, M s'' = P - A s^1.5, so its largest overlap is (5 P / (2 A))^(2/3) (energy
conservation) and its period 2 sqrt(M d / (2 P)) (2/3) B(1/3, 1/2); damped, it settles at
Hertz's static overlap (P / A)^(2/3); the drive's work is int P ds and eq. (11) holds at every
step; a restarted run equals the straight one; bad input is refused naming the field."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.special import beta

import granplate as gp
from granplate.errors import ScenarioError
from granplate.setup.io import from_dict
from granplate.setup.materials import LIBRARY
from granplate.setup.validate import validate

R = 0.005
P = 10.0  # the piston's force [N]
M = 0.01  # its mass [kg]


def hertz_wall(r: float) -> float:
    """A = 4/3 E* sqrt(R) of a steel sphere on a rigid wall [N/m^1.5] (eq. 2)."""
    m = LIBRARY["steel"]
    return 4.0 / 3.0 * m.E / (1.0 - m.nu**2) * math.sqrt(r)


def piston(dimension: int = 2, alpha_n: float = 0.0, t_end: float = 2.5e-4, **drive) -> dict:
    """A sphere held by a zero-velocity drive, touching a wall above it that a constant
    force P pushes down as a piston of mass M (drive: its drive's changes)."""
    z = {"z": 0.0} if dimension == 3 else {}
    vec = lambda *c: list(c[:dimension])
    d = {
        "name": "piston",
        "dimension": dimension,
        "contact": {"mu": 0.0, "alpha_n": alpha_n, "pairs": []},
        "time": {"t_end": t_end, "dt_max": 1e-7, "dt_initial": 1e-7, "output_interval": 1e-6, "field_interval": 1e-6},
        "solver": {"scheme": "verlet"},
        "granules": [{"label": "s", "x": 0.0, "y": R, "radius": R, "material": "steel", **z}],
        "walls": [{"label": "top", "normal": vec(0.0, 1.0, 0.0), "offset": 2.0 * R}],
        "drives": [
            {"target": "granule s", "kind": "velocity", "direction": vec(0.0, 1.0, 0.0), "profile": "constant"},
            {
                "target": "wall top",
                "kind": "force",
                "direction": vec(0.0, -1.0, 0.0),
                "profile": "constant",
                "value": P,
                "mass": M,
                **drive,
            },
        ],
    }
    if dimension == 2:
        d["load"] = {"kind": "none"}
    return d


def _peak(t: np.ndarray, s: np.ndarray) -> tuple[float, float]:
    """(time, value) of the first maximum of s, by the parabola through its three samples."""
    k = int(np.argmax(np.diff(s) < 0.0))
    a, b, c = s[k - 1 : k + 2]
    x = 0.5 * (a - c) / (a - 2.0 * b + c)
    return float(t[k] + x * (t[1] - t[0])), float(b - 0.25 * (a - c) * x)


@pytest.mark.parametrize("dimension", [2, 3])
def test_piston_on_a_held_sphere_rings_as_a_mass_on_a_hertz_spring(dimension):
    """Undamped, from rest at first touch: the overlap (the piston's displacement) peaks at
    (5 P / (2 A))^(2/3) half a period in, the period being the closed form's; the wall's force
    is A s^1.5 and the held sphere's drive takes it; drive_force is P, E_drive is P s, and
    eq. (11) holds at every step."""
    ds = gp.simulate(from_dict(piston(dimension)), progress=False)
    t = ds.time.values
    s = ds.drive_displacement.sel(drive="wall top").values
    a = hertz_wall(R)
    d_max = (2.5 * P / a) ** (2.0 / 3.0)
    period = 2.0 * math.sqrt(M * d_max / (2.0 * P)) * (2.0 / 3.0) * beta(1.0 / 3.0, 0.5)
    t_peak, s_peak = _peak(t, s)
    assert s_peak == pytest.approx(d_max, rel=1e-5)
    assert 2.0 * t_peak == pytest.approx(period, rel=1e-5)
    assert t[-1] > period and s[np.argmin(np.abs(t - period))] < 1e-2 * d_max  # back at first touch
    wf = ds.wall_force.sel(wall="top").values
    np.testing.assert_allclose(wf, a * np.maximum(s, 0.0) ** 1.5, rtol=1e-9, atol=1e-9 * P)
    np.testing.assert_allclose(ds.drive_force.sel(drive="granule s").values, wf, rtol=1e-9, atol=1e-9 * P)
    np.testing.assert_allclose(ds.drive_force.sel(drive="wall top").values, P)
    np.testing.assert_allclose(ds.E_drive.values, P * s, rtol=1e-4, atol=1e-4 * P * d_max)
    assert float(np.abs(ds.energy_residual_max).max()) < 1e-4


def test_the_pistons_energy_error_is_second_order():
    """Eq. (11)'s residual of the undamped piston is Verlet's own error at its contact: it
    falls 4x when the step halves (measured 1.29e-5, 3.22e-6, 8.0e-7 at 200, 100, 50 ns)."""
    res = []
    for dt in (2e-7, 1e-7):
        d = piston(3, t_end=1.5e-4)
        d["time"].update(dt_max=dt, dt_initial=dt)
        res.append(float(np.abs(gp.simulate(from_dict(d), progress=False).energy_residual_max).max()))
    assert 3.5 < res[0] / res[1] < 4.5


def test_damped_piston_settles_at_hertz_static_overlap_and_balances_energy():
    """Damped (alpha_n = 2), the piston comes to rest at Hertz's static overlap
    (P / A)^(2/3), its kinetic energy and the contact's dissipation in eq. (11) at every step:
    at rest E_drive = P s, of which the contact stores (2/5) A s^2.5 = (2/5) P s and the
    damping has dissipated the other 3/5."""
    ds = gp.simulate(from_dict(piston(3, alpha_n=2.0, t_end=8e-4)), progress=False)
    s = ds.drive_displacement.sel(drive="wall top").values
    a = hertz_wall(R)
    d_static = (P / a) ** (2.0 / 3.0)
    assert s[-1] == pytest.approx(d_static, rel=1e-8)
    assert ds.wall_force.sel(wall="top").values[-1] == pytest.approx(P, rel=1e-8)
    assert float(np.abs(ds.energy_residual_max).max()) < 1e-4
    end = ds.isel(time=-1)
    assert float(end.E_drive) == pytest.approx(P * d_static, rel=1e-5)
    assert float(end.D_viscous) == pytest.approx(0.6 * P * d_static, rel=1e-5)


def test_a_restarted_piston_run_equals_the_straight_one():
    """The piston's position and velocity are part of the restart state: a run restarted at
    t1 and continued to t2 equals one run straight to t2 (to round-off)."""
    s = from_dict(piston(2, alpha_n=0.2, t_end=1e-4))
    straight = gp.simulate(s, progress=False)
    first = gp.simulate(s, t_end=4e-5, progress=False)
    cont = gp.simulate(s, start_from=first, progress=False)
    a = straight.drive_displacement.sel(drive="wall top").values[-1]
    b = cont.drive_displacement.sel(drive="wall top").values[-1]
    assert b == pytest.approx(a, rel=1e-9)
    assert float(cont.E_drive[-1]) == pytest.approx(float(straight.E_drive[-1]), rel=1e-9)


BAD = [
    ({"mass": 0.0}, {}, "drives[1].mass"),
    ({"mass": -1.0}, {}, "drives[1].mass"),
    ({"mass": 2e6}, {}, "drives[1].mass"),
    ({"mass": math.nan}, {}, "drives[1].mass"),
    ({"direction": [1.0, 0.0]}, {}, "drives[1].direction"),
    ({"direction": [0.6, -0.8]}, {}, "drives[1].direction"),
]


@pytest.mark.parametrize("drive, solver, field", BAD, ids=[f"{f}-{k}" for k, (_, _, f) in enumerate(BAD)])
def test_bad_force_driven_wall_refused_naming_the_field(drive, solver, field):
    """A force drive on a wall without a mass in range, or along anything but the wall's
    normal, is refused before anything runs, naming the field."""
    d = piston(2, **drive)
    d["solver"].update(solver)
    with pytest.raises(ScenarioError) as e:
        validate(from_dict(d))
    assert e.value.field == field, str(e.value)


def test_a_mass_on_any_other_drive_is_refused():
    """`mass` is read by a force drive on a wall only: on a granule's drive it is refused."""
    d = piston(2)
    d["drives"][0]["mass"] = 1.0
    with pytest.raises(ScenarioError) as e:
        validate(from_dict(d))
    assert e.value.field == "drives[0].mass"


def test_a_piston_scenario_round_trips_and_others_are_written_as_before():
    """A force drive's `mass` survives TOML writing and reading; a drive without it is
    written without the key (every earlier scenario's text unchanged)."""
    from granplate.setup.io import dumps, loads

    s = from_dict(piston(2))
    assert loads(dumps(s)) == s and "mass = 0.01" in dumps(s)
    assert "mass" not in dumps(from_dict({**piston(2), "drives": piston(2)["drives"][:1]}))

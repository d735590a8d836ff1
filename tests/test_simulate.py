"""End-to-end runs: the energy balance (eq. 11) for every preset, the paper's E_shock,
sliding-to-rolling, netCDF round trip, and runs that go wrong stop with a message."""

from __future__ import annotations

import numpy as np
import pytest

import granplate as gp
from granplate.errors import SimulationError
from granplate.setup.presets import preset, preset_names
from granplate.setup.io import with_changes

from conftest import sphere_on_wall

# the shock lasts 1e-5 s: by 2e-5 s all of E_shock is in
SHORT = 2e-5


@pytest.fixture(scope="module")
def short_runs():
    return {name: gp.simulate(preset(name), t_end=SHORT, progress=False) for name in preset_names()}


@pytest.mark.parametrize(
    "name", ["bare-plate", "steel-r1", "steel-r05", "ptfe-r05", "ptfe-r05-moderate", "ptfe-r05-weak"]
)
def test_energy_balance_every_preset(short_runs, name):
    """E_p + E_g + D = E_shock at every output time, to the default tolerance 1e-4."""
    ds = short_runs[name]
    assert float(ds.E_shock[-1]) > 0
    lhs = ds.E_plate + ds.E_granular + ds.D_viscous + ds.D_friction
    scale = float(ds.E_shock.max())
    assert float(np.abs(lhs - ds.E_shock).max()) / scale < 1e-4
    assert float(np.abs(ds.energy_residual_max).max()) < 1e-4
    assert float(ds.D_viscous.min()) >= 0 and float(ds.D_friction.min()) >= 0


def test_e_shock_bare_plate_matches_paper(short_runs):
    """Bare plate, q0 = 50 kN/m on its edge: E_shock = 1.53e-2 J (paper section 3), 1%."""
    assert float(short_runs["bare-plate"].E_shock[-1]) == pytest.approx(1.53e-2, rel=0.01)


def test_e_shock_steel_r1_matches_paper(short_runs):
    """Steel packing R2 = R1: E_shock = 7.48e-4 J (paper section 3), 1%."""
    assert float(short_runs["steel-r1"].E_shock[-1]) == pytest.approx(7.48e-4, rel=0.01)


def test_shock_energy_scales_with_q0_squared(short_runs):
    """The shock is over before the wave is back: E_shock ~ impulse^2 ~ q0^2 (PTFE runs)."""
    e = {n: float(short_runs[n].E_shock[-1]) for n in ("ptfe-r05", "ptfe-r05-moderate", "ptfe-r05-weak")}
    assert e["ptfe-r05-moderate"] / e["ptfe-r05"] == pytest.approx((1 / 5) ** 2, rel=0.02)
    assert e["ptfe-r05-weak"] / e["ptfe-r05"] == pytest.approx((1 / 25) ** 2, rel=0.02)


def test_paper_topology(short_runs):
    """Steel R2 = R1 packing: 14 granules, contacts A..E on the plate, 2, 3, 4 loaded."""
    ds = short_runs["steel-r1"]
    assert list(ds.granule.values) == list("123456789ABCDE")
    assert list(ds.contact.values) == list("ABCDE")
    moved = np.abs(ds.vx.isel(time=10)).values > 0
    assert moved[[1, 2, 3]].all()


def test_sliding_sphere_ends_rolling_at_five_sevenths():
    """A sphere hitting a wall obliquely with enough friction ends rolling: the angular
    momentum about the contact point is conserved, so v_t = 5/7 v0 (tanh law, k_s large)."""
    v0 = 0.02
    ds = gp.simulate(sphere_on_wall(vx=v0, vy=-1.0, mu=0.5, t_end=1.2e-4), progress=False)
    vx, om = float(ds.vx[-1, 0]), float(ds.omega[-1, 0])
    assert vx == pytest.approx(5 / 7 * v0, rel=2e-3)
    assert vx + 0.01 * om == pytest.approx(0.0, abs=1e-4 * v0)  # rolling: v + R omega = 0 on the floor
    assert float(ds.vy[-1, 0]) == pytest.approx(1.0, rel=1e-6)  # elastic normal rebound


def test_netcdf_round_trip(short_runs, tmp_path):
    """A written result reads back equal, with units and the scenario embedded."""
    ds = short_runs["steel-r1"]
    path = gp.write(ds, tmp_path / "r.nc")
    back = gp.read(path)
    np.testing.assert_array_equal(back.E_plate.values, ds.E_plate.values)
    assert back.E_plate.attrs["units"] == "J"
    assert gp.loads(back.attrs["scenario_toml"]).name == "steel-r1"


def test_energy_residual_breach_stops_with_partial_result():
    """A tolerance the run cannot meet stops it with a message naming time and residual,
    and the error carries the outputs computed so far."""
    s = with_changes(preset("steel-r1"), {"solver.energy_tol": 1e-14})
    with pytest.raises(SimulationError) as err:
        gp.simulate(s, t_end=1e-5, progress=False)
    msg = str(err.value)
    assert "energy balance" in msg and "solver.energy_tol" in msg and "t = " in msg
    assert err.value.result is not None and err.value.result.sizes["time"] >= 1


def test_nonconvergence_stops_naming_the_contact():
    """An interface iteration that cannot converge (max_iterations = 1 with dt_min at the
    initial step) stops naming the plate contact, |N|, the slip rate and |lambda|."""
    s = with_changes(preset("steel-r1"), {"solver.scheme": "paper", "solver.max_iterations": 1, "time.dt_min": 4e-8})
    with pytest.raises(SimulationError) as err:
        gp.simulate(s, t_end=2e-4, progress=False)
    msg = str(err.value)
    assert "plate contact '" in msg and "|N| =" in msg and "lambda" in msg
    assert err.value.result.sizes["time"] > 1


def test_step_control_keeps_local_maps_contractive():
    """Criterion (8), paper scheme: every recorded |lambda| stays below 1 (near the 0.5 target)."""
    ds = gp.simulate(with_changes(preset("steel-r1"), {"solver.scheme": "paper"}), t_end=SHORT, progress=False)
    lam = ds.local_map_modulus
    assert float(lam.max()) < 1.0


@pytest.mark.parametrize(
    "name,changes",
    [
        ("ptfe-r05", {}),
        ("bare-plate", {}),
        ("steel-r05", {"solver.scheme": "paper"}),
        ("ptfe-r05", {"plate.modes": "truncated"}),
    ],
)
def test_summary_only_run_gives_the_full_runs_summary(short_runs, name, changes):
    """A summary-only run (no plate fields) has gp.summary and granule masses bit for bit
    equal to those of the whole Dataset, with a full or a truncated plate basis."""
    s = with_changes(preset(name), changes) if changes else preset(name)
    full = short_runs[name] if not changes else gp.simulate(s, t_end=SHORT, progress=False)
    light = gp.simulate(s, t_end=SHORT, progress=False, summary_only=True)
    a, b = gp.summary(full), gp.summary(light)
    for key in ("wall_time_s", "loop_time_s", "compile_time_s"):  # the machine's, not the run's
        a.pop(key), b.pop(key)
    assert a == b and a["max_von_mises"] > 0
    assert np.array_equal(full["mass"].values, light["mass"].values)
    assert "plate_ux" not in light and "plate_ux" in full


@pytest.mark.parametrize("v", [0.0, 0.5])
def test_initial_energy_is_the_kinetic_energy_of_the_initial_velocities(v):
    """E_initial = sum 1/2 m v^2 exactly (0 from rest), although two spheres touching at
    x = R and 3R overlap by round-off (2R - (0.03 - 0.01) = 3.5e-18 m) and store ~1e-35 J."""
    from conftest import two_spheres

    ds = gp.simulate(two_spheres(v, t_end=2e-7, out=1e-7), progress=False)
    assert float(ds.E_contact[0]) > 0.0  # the round-off energy is there ...
    m = 7850.0 * 4.0 / 3.0 * np.pi * 0.01**3
    assert ds.attrs["E_initial"] == pytest.approx(2 * 0.5 * m * v**2, rel=1e-14, abs=0.0)  # ... but not counted
    assert gp.summary(ds)["e_initial"] == ds.attrs["E_initial"]

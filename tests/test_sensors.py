"""Force sensors in granules ([[sensors]], docs/model.md section 3.15): the truth is statics
(a chain at rest under F0 reads F0 at every bead, plus the weight above it under gravity),
Hertz's law recomputed from the recorded positions (a head-on impact sampled finer than the
output), the plate contact's recorded force, a granule in touch with nothing (0), sample
times on k * sensor_interval, runs whose outputs sensors leave bitwise unchanged, and bad
input refused naming the field."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import granplate as gp
from granplate.errors import ScenarioError, YieldWarning
from granplate.model.arrays import build_model
from granplate.results import spectra
from granplate.setup.materials import LIBRARY
from granplate.setup.scenario import Sensor
from granplate.setup.validate import validate
from granplate.solver.driver import sensor_times
from granplate.verification.face_contacts import drop_scenario, node_spacing

# (steel at these speeds and preloads passes Hertz's yield onset: the elastic law is the truth here)
pytestmark = pytest.mark.filterwarnings("ignore", category=YieldWarning)

CHAIN = """
name = "sensed-chain"
dimension = {dimension}
[layout]
kind = "chain"
count = 6
radius = 0.005
material = "steel"
[precompression]
target = "wall {wall}"
force = 10.0
[time]
t_end = 2e-6
dt_initial = 1e-8
dt_max = 1e-8
output_interval = 1e-6
field_interval = 1e-6
sensor_interval = 2.5e-7
[solver]
scheme = "verlet"
"""
SENSORS = "".join(f'[[sensors]]\ngranule = "c{k}"\n' for k in range(1, 7))


def _chain(dimension=3, wall="xmax", extra=""):
    """Six steel beads of radius 5 mm in a row along x between two walls, pressed by 10 N
    from the wall `wall`, a sensor in each (c1 at x = 5 mm)."""
    text = CHAIN.format(dimension=dimension, wall=wall)
    if dimension == 2:  # the plane's chain layout has one wall: the beads and both walls by hand
        beads = "".join(
            f'[[granules]]\nlabel = "c{k + 1}"\nx = {0.005 + 0.01 * k!r}\ny = 0.005\nradius = 0.005\n'
            'material = "steel"\n'
            for k in range(6)
        )
        walls = (
            '[[walls]]\nlabel = "left"\nnormal = [-1.0, 0.0]\noffset = 0.0\n'
            '[[walls]]\nlabel = "right"\nnormal = [1.0, 0.0]\noffset = 0.06\n[load]\nkind = "none"\n'
        )
        head, _, tail = text.partition("[precompression]")
        text = head.split("[layout]")[0] + beads + walls + "[precompression]" + tail
    return gp.loads(text + SENSORS + extra)


@pytest.mark.parametrize("dimension, wall", [(3, "xmax"), (2, "right")])
def test_every_bead_of_a_chain_at_rest_reads_the_precompression(dimension, wall):
    """Six beads pressed by F0 = 10 N between two walls: every contact carries F0, so every
    bead (the end ones between a wall and a bead too) reads (F0 + F0) / 2 = F0 at every sample,
    to the static state's tolerance (1e-8 of F0)."""
    ds = gp.simulate(_chain(dimension, wall), progress=False)
    f = ds["sensor_force"]
    assert f.dims == ("sensor_time", "sensor")
    assert list(ds["sensor"].values) == [f"c{k}" for k in range(1, 7)]
    assert f.attrs["units"] == "N"
    assert ds.sizes["sensor_time"] == 9
    np.testing.assert_allclose(f.values, 10.0, rtol=1e-7)


def test_under_gravity_each_bead_reads_the_weight_above_it_and_half_its_own():
    """A vertical chain (gravity along -x) pressed from the top by F0: the bead k-th from the
    top sits between contacts carrying F0 + (k - 1) m g and F0 + k m g, so reads
    F0 + (k - 1/2) m g."""
    g = 9.81
    s = _chain(extra=f"[gravity]\ng = [{-g}, 0.0, 0.0]\n")
    m = float(build_model(s).granular.mass[0])
    ds = gp.simulate(s, progress=False)
    k_from_top = 6 - np.arange(6)  # c1 is the bottom bead
    expected = np.broadcast_to(10.0 + (k_from_top - 0.5) * m * g, (9, 6))
    np.testing.assert_allclose(ds["sensor_force"].values, expected, rtol=1e-7)


IMPACT = """
name = "sensed-impact"
dimension = {dimension}
[[granules]]
label = "a"
x = 0.0
y = 0.0
radius = 0.005
material = "steel"
vx = 0.5
[[granules]]
label = "b"
x = 0.01
y = 0.0
radius = 0.005
material = "steel"
[[granules]]
label = "lone"
x = 0.05
y = 0.05
radius = 0.005
material = "steel"
[load]
kind = "none"
[contact]
alpha_n = 0.0
mu = 0.0
[time]
t_end = 4e-5
dt_initial = 1e-8
dt_max = 1e-8
output_interval = 1e-6
field_interval = 1e-6
sensor_interval = {interval}
[solver]
scheme = "{scheme}"
implicit_dt_max = 1e-6
[[sensors]]
granule = "a"
name = "striker"
[[sensors]]
granule = "lone"
"""


def _impact(scheme="verlet", dimension=3, interval="1e-7", sensors=True):
    text = IMPACT.format(scheme=scheme, dimension=dimension, interval=interval)
    return gp.loads(text if sensors else text.split("[[sensors]]")[0])


def _hertz_force(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Hertz's N = 4/3 E* sqrt(R*) delta^(3/2) of two steel spheres of radius 5 mm at the
    centres (x, y) [m] of a and b (time, granule), from the material's E and nu alone."""
    steel = LIBRARY["steel"]
    e_star = steel.E / (2.0 * (1.0 - steel.nu**2))
    a = 4.0 / 3.0 * e_star * math.sqrt(0.005 / 2.0)
    delta = 0.01 - np.hypot(x[:, 1] - x[:, 0], y[:, 1] - y[:, 0])
    return a * np.maximum(delta, 0.0) ** 1.5


@pytest.mark.parametrize("scheme, dimension", [("verlet", 3), ("verlet", 2), ("paper", 2), ("implicit", 2)])
def test_a_sensor_sampled_finer_than_the_output_reads_hertz_at_the_recorded_states(scheme, dimension):
    """A steel sphere striking another head-on at 0.5 m/s, sampled every 0.1 us with the output
    every 1 us: at the output times, the striker's sensor reads half of Hertz's force
    recomputed from the recorded centres (its one contact); between them the samples trace
    the pulse (its peak within 1% of the closed-form peak of an elastic impact); the granule in
    touch with nothing reads 0; the samples lie on k * 0.1 us."""
    ds = gp.simulate(_impact(scheme, dimension), progress=False)
    t_s = ds["sensor_time"].values
    k = np.arange(len(t_s))
    assert len(t_s) == 401
    np.testing.assert_allclose(t_s, k * 1e-7, rtol=0.0, atol=1e-9 * 1e-7)
    shared = np.flatnonzero(np.isin(t_s, ds["time"].values))
    assert len(shared) == ds.sizes["time"]
    reading = ds["sensor_force"].sel(sensor="striker").values
    hertz = _hertz_force(ds["x"].values, ds["y"].values)
    assert hertz.max() > 100.0
    np.testing.assert_allclose(reading[shared], 0.5 * hertz, rtol=1e-9, atol=1e-9 * hertz.max())
    steel = LIBRARY["steel"]
    m_star = 0.5 * 4.0 / 3.0 * math.pi * 0.005**3 * steel.rho
    a = 4.0 / 3.0 * steel.E / (2.0 * (1.0 - steel.nu**2)) * math.sqrt(0.005 / 2.0)
    peak = a * (5.0 * m_star * 0.5**2 / (4.0 * a)) ** 0.6  # Hertz's largest force, v = 0.5 m/s
    assert 0.5 * peak == pytest.approx(reading.max(), rel=0.01)
    assert np.all(ds["sensor_force"].sel(sensor="lone").values == 0.0)


def test_sensors_leave_the_run_unchanged():
    """Sampled at the output times (sensor_interval absent), sensors add no step: the
    outputs are bitwise those of the run without them."""
    a = gp.simulate(_impact(interval="1e-6"), progress=False)
    b = gp.simulate(_impact(interval="1e-6", sensors=False), progress=False)
    assert "sensor_force" not in b
    for name in ("x", "vx", "E_granular", "energy_residual"):
        np.testing.assert_array_equal(a[name].values, b[name].values)
    np.testing.assert_array_equal(a["sensor_time"].values, a["time"].values)


def test_a_granule_on_the_plate_reads_half_its_plate_contact_force():
    """A granule thrown at the paper's plate between two nodes (a patch contact formed during
    the run, "paper" scheme): its one contact is the plate's, so it reads half the plate
    contact's recorded normal force at every output time."""
    s = drop_scenario(0.05 + 0.37 * node_spacing(40), gap=1e-5, t_end=6e-5, out=1e-6, scheme="paper")
    s = dataclasses.replace(s, sensors=(Sensor(granule="g"),), time=dataclasses.replace(s.time, sensor_interval=2.5e-7))
    ds = gp.simulate(s, progress=False)
    fn = ds["contact_normal_force"].values[:, 0]
    assert fn.max() > 10.0
    shared = np.isin(ds["sensor_time"].values, ds["time"].values)
    np.testing.assert_allclose(ds["sensor_force"].values[shared, 0], 0.5 * fn, rtol=1e-12)


def test_sample_times_land_on_the_output_times_they_meet():
    """Sample times k * interval within 1e-9 intervals of an output time are that output
    time (one step lands on both); none beyond t_end, none before the run's first output."""
    out = np.arange(11) * 0.1
    ts = sensor_times(0.0, 1.0, 0.1 / 3.0, out)
    assert len(ts) == 31
    assert set(out).issubset(set(ts))
    assert ts[-1] == 1.0
    assert sensor_times(0.5, 1.0, 0.1 / 3.0, out)[0] == pytest.approx(0.5)


def test_a_sensor_signal_has_a_spectrum_on_its_own_time_axis():
    """sensor_force:NAME is a signal on sensor_time; a table mixing it with a signal on the
    output's time axis is refused naming --signal."""
    import xarray as xr

    t = np.arange(64) * 1e-7
    ds = xr.Dataset(coords={"time": t[::4], "wall": ["floor"], "sensor_time": t, "sensor": ["s"]})
    ds["wall_force"] = (("time", "wall"), np.ones((16, 1)), {"units": "N"})
    ds["sensor_force"] = (("sensor_time", "sensor"), np.sin(2e6 * np.pi * t)[:, None], {"units": "N"})
    tt, x, unit = spectra.signal(ds, "sensor_force:s")
    assert len(tt) == 64 and unit == "N"
    table = spectra.spectrum_table(ds, ["sensor_force:s"])
    assert table.sizes["frequency"] == 33
    with pytest.raises(ScenarioError, match="separate spectra") as e:
        spectra.spectrum_table(ds, ["wall_force:floor", "sensor_force:s"])
    assert e.value.field == "--signal"
    assert list(spectra.spectrum_table(ds, [])["signal"].values) == ["wall_force:floor"]


@pytest.mark.parametrize(
    "extra, field, match",
    [
        ('[[sensors]]\ngranule = "c9"\n', "sensors[6].granule", "no granule is labelled 'c9'"),
        ('[[sensors]]\ngranule = "c2"\n', "sensors[6].granule", "named 'c2' already"),
        ('[[sensors]]\ngranule = "c2"\nname = "c3"\n', "sensors[6].name", "named 'c3' already"),
        ("[[sensors]]\ngranule = 3\n", "sensors[6].granule", "expected a string"),
    ],
)
def test_bad_sensors_are_refused_naming_the_field(extra, field, match):
    """An unknown granule, a name two sensors share, a granule given as a number."""
    with pytest.raises(ScenarioError, match=match) as e:
        validate(_chain(extra=extra))
    assert e.value.field == field


@pytest.mark.parametrize(
    "interval, match",
    [("0.0", "must be > 0"), ("-1e-7", "must be > 0"), ("nan", "finite"), ("inf", "finite"), ("1e-3", "t_end")],
)
def test_a_bad_sensor_interval_is_refused(interval, match):
    """time.sensor_interval must be finite, > 0 and at most t_end."""
    text = CHAIN.format(dimension=3, wall="xmax").replace("sensor_interval = 2.5e-7", f"sensor_interval = {interval}")
    with pytest.raises(ScenarioError, match=match) as e:
        validate(gp.loads(text + SENSORS))
    assert e.value.field == "time.sensor_interval"


def test_too_many_samples_are_refused_before_the_run():
    """More samples x sensors than MAX_SENSOR_VALUES (2^26) is refused naming the interval."""
    text = CHAIN.format(dimension=3, wall="xmax").replace("sensor_interval = 2.5e-7", "sensor_interval = 1e-13")
    with pytest.raises(ScenarioError, match="2\\^26") as e:
        validate(gp.loads(text + SENSORS))
    assert e.value.field == "time.sensor_interval"


def test_sensors_are_written_and_read_back():
    """A scenario with sensors written as TOML reads back equal; one without writes no
    [[sensors]] and no sensor_interval (every scenario written before is written as before)."""
    s = _chain()
    assert gp.loads(gp.dumps(s)) == s
    plain = gp.loads(CHAIN.format(dimension=3, wall="xmax").replace("sensor_interval = 2.5e-7\n", ""))
    assert "sensor" not in gp.dumps(plain)


def test_a_restarted_run_samples_its_sensors_as_the_straight_run():
    """A run restarted at t1 = 20 us from a result's stored state samples its sensors from t1
    on, at the straight run's times and with its readings, bitwise."""
    s = _impact()
    straight = gp.simulate(s, progress=False)
    first = gp.simulate(s, progress=False, t_end=2e-5)
    assert float(first["sensor_time"][-1]) == pytest.approx(2e-5)
    restarted = gp.simulate(s, progress=False, start_from=first)
    t = restarted["sensor_time"].values
    assert t[0] == pytest.approx(2e-5) and len(t) == 201
    later = straight["sensor_time"].values >= t[0] - 1e-9 * 1e-7  # (t1: the first run's end, to rounding)
    np.testing.assert_allclose(t, straight["sensor_time"].values[later], rtol=0.0, atol=1e-9 * 1e-7)
    np.testing.assert_array_equal(restarted["sensor_force"].values, straight["sensor_force"].values[later])


BLOCK_DROP = """
name = "sensed-drop"
dimension = 3
[[granules]]
label = "ball"
x = 0.0103
y = 0.0096
z = 0.01201
radius = 0.002
material = "steel"
vz = -1.0
[plate]
size = [0.02, 0.02, 0.01]
elements = [3, 3, 2]
material = "steel"
clamped = ["zmin"]
patch_radius = 0.0
max_frequency = 1.5e5
[load]
kind = "none"
[contact]
alpha_n = 0.0
mu = 0.0
[time]
t_end = 2.4e-5
dt_max = 2e-8
output_interval = 1e-6
field_interval = 2.4e-5
sensor_interval = 2e-7
[solver]
scheme = "verlet"
granular_friction = "split"
[[sensors]]
granule = "ball"
"""


def test_a_sphere_on_an_elastic_solid_reads_half_its_contact_force():
    """A steel sphere dropped on a clamped steel block (an elastic solid in space): its one
    contact is the body's, so at every output time it reads half the body contact's normal
    force, which the result replays from the recorded state."""
    ds = gp.simulate(gp.loads(BLOCK_DROP), progress=False)
    fn = ds["body_contact_normal_force"].sel(granule="ball").values
    assert fn.max() > 10.0
    shared = np.isin(ds["sensor_time"].values, ds["time"].values)
    assert shared.sum() == ds.sizes["time"] and ds.sizes["sensor_time"] == 121
    np.testing.assert_allclose(ds["sensor_force"].values[shared, 0], 0.5 * fn, rtol=1e-9, atol=1e-9 * fn.max())


def test_the_sensor_figure_draws_each_sensors_samples():
    """granplate plot's sensor-forces figure: one curve per sensor, its samples against
    sensor_time in ms."""
    from granplate.figures import run as figures

    ds = gp.simulate(_impact(), progress=False)
    fig = figures.figures(ds)["sensor-forces"]
    lines = {ln.get_label(): ln for ln in fig.axes[0].get_lines()}
    np.testing.assert_array_equal(lines["striker"].get_ydata(), ds["sensor_force"].sel(sensor="striker").values)
    np.testing.assert_allclose(lines["lone"].get_xdata(), 1e3 * ds["sensor_time"].values)

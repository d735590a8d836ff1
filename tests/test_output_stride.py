"""The output stride of a run of many granules (setup.output_stride): the truth is the
rule's own statement, checked by brute force over the strides (the smallest k whose output
times times the granules stay within GRANULE_VALUES_MAX), a run whose outputs are those of
the same scenario given the raised output interval (bit for bit), and the user's
time.field_interval taking precedence."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from granplate.setup import output_stride as O
from granplate.setup.io import loads

#: Three steel spheres in space, one launched at another; 2,001 output times by default.
THREE = """
name = "three"
dimension = 3
[[granules]]
x = 0.005
y = 0.01
z = 0.01
radius = 0.002
material = "steel"
vx = 1.5
[[granules]]
x = 0.0095
y = 0.01
z = 0.01
radius = 0.0025
material = "steel"
[[granules]]
x = 0.02
y = 0.01
z = 0.01
radius = 0.003
material = "steel"
[solver]
scheme = "verlet"
[time]
t_end = 2e-5
dt_initial = 1e-8
dt_max = 1e-8
output_interval = 1e-7
"""


def _time(s, **kw):
    return dataclasses.replace(s, time=dataclasses.replace(s.time, **kw))


@pytest.mark.parametrize("cap", [603, 600, 100, 31, 7, 6, 5, 3])
def test_the_stride_is_the_smallest_that_keeps_the_values_within_the_cap(monkeypatch, cap):
    monkeypatch.setattr(O, "GRANULE_VALUES_MAX", cap)
    s = loads(THREE)  # 3 granules, 201 output times: 603 values
    k = O.output_stride(s)
    n = O.output_count(s.time.t_end, s.time.output_interval)
    fits = [j for j in range(1, n) if 3 * O.output_count(s.time.t_end, j * s.time.output_interval) <= cap]
    assert k == (fits[0] if fits else n - 1)
    r = O.with_output_stride(s)
    assert r.time.output_interval == min(k * 1e-7, s.time.t_end)
    assert r.time.field_interval / r.time.output_interval == pytest.approx(
        round(r.time.field_interval / r.time.output_interval)
    )
    assert r.time.sensor_interval == (None if k == 1 else 1e-7)  # the sensors sample as before


def test_a_given_field_interval_is_the_stride(monkeypatch):
    monkeypatch.setattr(O, "GRANULE_VALUES_MAX", 33)
    s = loads(THREE)
    assert O.output_stride(s) == 20  # the smallest: 11 output times of 3 granules
    assert O.output_stride(_time(s, field_interval=5e-7)) == 5  # given: 41 output times, over the cap
    assert O.output_stride(_time(s, field_interval=1e-7)) == 1
    monkeypatch.setattr(O, "GRANULE_VALUES_MAX", 10**9)
    assert O.output_stride(_time(s, field_interval=5e-7)) == 1  # within the cap: as given


@pytest.mark.filterwarnings("ignore::granplate.errors.YieldWarning")  # steel on steel yields: Hertz is timed
def test_a_strided_run_is_the_run_at_the_raised_interval(monkeypatch):
    """The run of the strided scenario outputs what the scenario given the raised output
    interval does; its summary says so, and it restarts from its own result."""
    import granplate as gp
    from granplate.cli import format_summary
    from granplate.results.dataset import summary

    monkeypatch.setattr(O, "GRANULE_VALUES_MAX", 63)  # 21 output times of 3 granules
    s = _time(loads(THREE), restart_interval=1e-5)
    ds = gp.simulate(s, progress=False)
    assert ds.sizes["time"] == 21 and ds.attrs["output_stride"] == 10
    monkeypatch.setattr(O, "GRANULE_VALUES_MAX", 10**9)
    raised = gp.simulate(_time(s, output_interval=1e-6, sensor_interval=1e-7), progress=False)
    assert "output_stride" not in raised.attrs
    for k in ("time", "x", "vx", "E_granular", "energy_residual"):
        np.testing.assert_array_equal(ds[k].values, raised[k].values, err_msg=k)
    assert float(np.abs(ds.vx.values[-1] - ds.vx.values[0]).max()) > 0.0  # they collided
    text = format_summary(summary(ds))
    assert "one output time in 10" in text and "time.output_interval 1e-07 s raised to 1e-06 s" in text
    monkeypatch.setattr(O, "GRANULE_VALUES_MAX", 63)
    late = gp.simulate(_time(s, t_end=2e-5), start_from=ds, start_time=1e-5)
    np.testing.assert_array_equal(late.x.values, ds.x.values[10:])
    assert math.isclose(float(late.time[0]), 1e-5)

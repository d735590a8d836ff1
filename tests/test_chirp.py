"""The chirp drive profile (docs/model.md section 3.11): a displacement swept linearly in
frequency, against its closed form a sin(2 pi (f0 t + (f1 - f0) t^2 / (2 T))) at the output
times; a chirp force on a free granule against m x'' = F; a velocity chirp refused."""

from __future__ import annotations

import math

import numpy as np
import pytest

import granplate as gp
from granplate.errors import ScenarioError
from granplate.setup.io import from_dict
from granplate.setup.validate import validate

from test_drives import R, base


def chirp(t, a=1e-6, f0=2e3, f1=2e4, T=4e-4):
    """The closed form of the chirp, held at its last value after T."""
    tt = np.minimum(t, T)
    return a * np.sin(2.0 * math.pi * (f0 * tt + 0.5 * (f1 - f0) * tt * tt / T))


def chirp_drive(kind="displacement", **extra) -> dict:
    d = {
        "target": "granule p",
        "kind": kind,
        "direction": [1.0, 0.0],
        "profile": "chirp",
        "amplitude": 1e-6,
        "frequency": 2e3,
        "frequency_end": 2e4,
        "duration": 4e-4,
    }
    d.update(extra)
    return d


def test_a_chirp_displacement_follows_its_closed_form():
    """A granule moved by a displacement chirp: drive_displacement and its x are the closed
    form at every output time of the sweep (to 1e-4 of the amplitude), held after it (to one
    step's motion: the velocity stops inside a step)."""
    s = from_dict(
        base(
            granules=[{"label": "p", "x": 0.0, "y": 0.0, "radius": R, "material": "steel"}],
            drives=[chirp_drive()],
            time={"t_end": 5e-4, "dt_max": 1e-7, "dt_initial": 1e-7, "output_interval": 1e-6, "field_interval": 1e-6},
        )
    )
    ds = gp.simulate(s, progress=False)
    t = ds.time.values
    sweep = t <= 4e-4
    np.testing.assert_allclose(ds.drive_displacement.values[sweep, 0], chirp(t[sweep]), rtol=0, atol=1e-10)
    np.testing.assert_allclose(ds.x.values[sweep, 0], chirp(t[sweep]), rtol=0, atol=1e-10)
    # after it, held: the velocity's stop falls inside a step, one step's motion at most
    np.testing.assert_allclose(ds.x.values[~sweep, 0], chirp(t[~sweep]), rtol=0, atol=1e-6 * 2 * math.pi * 2e4 * 1e-7)


def test_a_chirp_force_accelerates_a_free_granule():
    """A chirp force F(t) on a free granule: its velocity is int F / m, which the fine-step
    velocity Verlet run follows to 1e-6 of its peak."""
    s = from_dict(
        base(
            granules=[{"label": "p", "x": 0.0, "y": 0.0, "radius": R, "material": "steel"}],
            drives=[chirp_drive("force", amplitude=2.0)],
            time={"t_end": 4e-4, "dt_max": 1e-8, "dt_initial": 1e-8, "output_interval": 1e-6, "field_interval": 1e-6},
        )
    )
    ds = gp.simulate(s, progress=False)
    t, m = ds.time.values, float(ds.mass[0])
    fine = np.linspace(0.0, t[-1], 400001)
    v = np.concatenate([[0.0], np.cumsum(0.5 * (chirp(fine[1:], a=2.0) + chirp(fine[:-1], a=2.0)) * np.diff(fine))])
    expected = np.interp(t, fine, v) / m
    np.testing.assert_allclose(ds.vx.values[:, 0], expected, rtol=0, atol=1e-6 * np.max(np.abs(expected)))


@pytest.mark.parametrize(
    "change, field",
    [({"kind": "velocity"}, "kind"), ({"frequency_end": 0.0}, "frequency_end"), ({"duration": 0.0}, "duration")],
)
def test_bad_chirps_are_refused_by_name(change, field):
    """A velocity chirp, a zero end frequency, a zero duration: refused naming the field."""
    s = from_dict(
        base(
            granules=[{"label": "p", "x": 0.0, "y": 0.0, "radius": R, "material": "steel"}],
            drives=[chirp_drive(**change)],
        )
    )
    with pytest.raises(ScenarioError) as e:
        validate(s)
    assert e.value.field == f"drives[0].{field}"

"""The drive profiles' registry (setup.drive_profiles.DRIVE_PROFILE_REGISTRY) and dispatch
(physics.drives). Truth: closed forms of a toy profile a user adds as one module and one
registry entry (a quadratic P = value (t / duration)^2), the registered profiles' own
closed forms through the dispatch, and the rules a registry entry carries."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numba import njit

from granplate.errors import ScenarioError
from granplate.physics import drives
from granplate.physics.dispatch import pick_of
from granplate.physics.profiles import N_PAR, PAR_AMPLITUDE, PAR_DURATION, PAR_VALUE
from granplate.setup import drive_profiles
from granplate.setup.drive_profiles import DRIVE_PROFILE_REGISTRY, DriveProfile
from granplate.setup.scenario import Drive

QUADRATIC = """
from granplate.jit import njit
from granplate.physics.profiles import PAR_DURATION, PAR_VALUE


@njit(cache=True, inline="always")
def profile_terms(t, par, tab, n):
    v = par[PAR_VALUE]
    T = par[PAR_DURATION]
    return v * t ** 3 / (3.0 * T * T), v * t * t / (T * T), 2.0 * v * t / (T * T), 2.0 * v / (T * T)
"""


def quadratic_speed(p, d, step_max):
    """The toy's rules: a duration > 0; a displacement's speed 2 |value| / duration at t = T."""
    if not d.duration > 0.0:
        raise ScenarioError(f"{p}.duration", d.duration, "must be > 0 [s]")
    return 2.0 * abs(d.value) / d.duration if d.kind == "displacement" else abs(d.value)


@pytest.fixture
def quadratic(tmp_path, monkeypatch):
    """The registry with the toy profile added as a user adds it (its module and one entry)."""
    (tmp_path / "granplate_toy_quadratic.py").write_text(QUADRATIC)
    monkeypatch.syspath_prepend(str(tmp_path))
    entry = DriveProfile("granplate_toy_quadratic", ("value", "duration"), quadratic_speed, "value")
    monkeypatch.setitem(DRIVE_PROFILE_REGISTRY, "quadratic", entry)
    names = list(DRIVE_PROFILE_REGISTRY)
    terms = pick_of(tuple(drives.profile_module(n).profile_terms for n in names), 4)

    @njit
    def call(pid, t, par, tab, n):
        return terms(pid, t, par, tab, n)

    return call, names.index("quadratic")


def test_a_new_profile_is_one_module_and_one_registry_entry(quadratic):
    """The toy profile is dispatched by its id, the next after the registered ones: its
    integral, value, slope and curvature v t^3 / 3T^2, v t^2 / T^2, 2 v t / T^2, 2 v / T^2;
    the registered ramp keeps its id and closed form."""
    call, pid = quadratic
    par = np.zeros(N_PAR)
    par[PAR_VALUE], par[PAR_DURATION] = 3.0, 2.0
    tab = np.zeros((1, 3))
    assert call(pid, 1.0, par, tab, 1) == pytest.approx((0.25, 0.75, 1.5, 1.5), rel=1e-15)
    ramp = list(DRIVE_PROFILE_REGISTRY).index("ramp")
    assert call(ramp, 1.0, par, tab, 1) == pytest.approx((0.75, 1.5, 1.5, 0.0), rel=1e-15)


def test_a_registry_entry_owns_its_rules(quadratic, monkeypatch):
    """The entry's fields and speed rule are the ones setup applies: a field the profile does
    not read is refused, its own rule names its field, a speed beyond the wave speed is
    named by the entry's speed_field."""
    from granplate.setup import drive_checks

    def drive(**fields):
        return Drive(target="granule a", kind="displacement", direction=(1.0, 0.0), profile="quadratic", **fields)

    with pytest.raises(ScenarioError, match="amplitude.*not read by profile 'quadratic'"):
        drive_checks._profile_fields("drives[0]", drive(value=1e-3, duration=1e-3, amplitude=1.0))
    with pytest.raises(ScenarioError, match=r"drives\[0\]\.duration.*must be > 0"):
        drive_checks._profile_values("drives[0]", drive(value=1e-3), 1e-6, 5000.0)
    with pytest.raises(ScenarioError, match=r"drives\[0\]\.value.*asks for a speed of 2000 m/s"):
        drive_checks._profile_values("drives[0]", drive(value=1.0, duration=1e-3), 1e-6, 1000.0)
    drive_checks._profile_values("drives[0]", drive(value=1e-3, duration=1e-3), 1e-6, 1000.0)


@pytest.mark.parametrize(
    "name, values, t, want",
    [
        ("constant", {PAR_VALUE: 2.0}, 0.5, (1.0, 2.0, 0.0, 0.0)),
        ("half-sine", {PAR_AMPLITUDE: 2.0, PAR_DURATION: 1.0}, 0.5, (2.0 / math.pi, 2.0, 0.0, -2.0 * math.pi**2)),
        (
            "harmonic",
            {PAR_VALUE: 1.0, PAR_AMPLITUDE: 2.0, 2: 0.25},
            1.0,
            (1.0 + 4.0 / math.pi, 3.0, 0.0, -(math.pi**2) / 2),
        ),
    ],
)
def test_each_registered_profile_gives_its_closed_form(name, values, t, want):
    """physics.drives.profile_terms, by the profile's registered id, gives its closed form."""
    par = np.zeros(N_PAR)
    for column, v in values.items():
        par[column] = v
    pid = list(DRIVE_PROFILE_REGISTRY).index(name)
    assert drives.profile_terms(t, pid, par, np.zeros((1, 3)), 1) == pytest.approx(want, rel=1e-12, abs=1e-12)


def test_every_registered_profile_module_gives_its_function():
    """Each entry's module gives profile_terms, and a module lacking it is refused naming it;
    the allowed names are the registry's."""
    for name in DRIVE_PROFILE_REGISTRY:
        assert callable(drives.profile_module(name).profile_terms)
    assert drive_profiles.DRIVE_PROFILES == tuple(DRIVE_PROFILE_REGISTRY)
    with pytest.MonkeyPatch.context() as mp:
        mp.setitem(DRIVE_PROFILE_REGISTRY, "broken", DriveProfile("granplate.physics.hertz", (), quadratic_speed, ""))
        with pytest.raises(ImportError, match="lacks profile_terms"):
            drives.profile_module("broken")

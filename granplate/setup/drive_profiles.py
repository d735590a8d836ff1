"""The drive profiles' registry (`Drive.profile`; docs/scenario.md, section "Drives"): each
profile's name, the module of its compiled time function (physics/profiles/, read by
physics.drives), the Drive fields it reads and its rules. A profile's id is its position
here. A new profile is its module and one entry (docs/architecture.md, "A load or a
drive"); the rules every drive obeys (target, kind, direction, the fields a profile does
not read) stay in setup.drive_checks, which calls the entry's `speed`.

Each entry's `speed(path, drive, step_max)` checks the values its fields take (raising
ScenarioError naming the field, before anything runs) and returns the largest speed [m/s]
the drive asks of its body (0 for a force drive); setup.drive_checks refuses one at or above
the materials' slowest wave speed, naming the entry's `speed_field`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable

from granplate.errors import ScenarioError
from granplate.setup.fields import is_number

#: a harmonic drive's period must hold at least this many of the scheme's largest steps
STEPS_PER_PERIOD = 20
#: the Drive fields a profile's parameters come from, in the order of the PAR_* columns
#: (physics.profiles), with their defaults (a field the profile does not read keeps it)
PAR_FIELDS: dict[str, float] = {"value": 0.0, "amplitude": 0.0, "frequency": 0.0, "duration": 0.0, "frequency_end": 0.0}


@dataclass(frozen=True)
class DriveProfile:
    """One drive profile: `module`, the module of its `profile_terms`; `fields`, the Drive
    fields it reads; `speed`, its rules and the largest speed it asks for (module doc);
    `speed_field`, the field a refused speed is named by."""

    module: str
    fields: tuple[str, ...]
    speed: Callable[[str, Any, float], float]
    speed_field: str


def _duration(p: str, d) -> None:
    """A profile over a duration: duration > 0 [s]."""
    if not d.duration > 0.0:
        raise ScenarioError(f"{p}.duration", d.duration, "must be > 0 [s]")


def _frequency_in_range(path: str, f: float, step_max: float) -> None:
    """0 < f <= the frequency whose period holds STEPS_PER_PERIOD of the scheme's largest steps."""
    f_max = 1.0 / (STEPS_PER_PERIOD * step_max)
    if not 0.0 < f <= f_max:
        raise ScenarioError(
            path,
            f,
            f"allowed 0 < frequency <= {f_max:.6g} Hz (a period of at least {STEPS_PER_PERIOD} steps of {step_max:g} s)",
        )


def constant_speed(p: str, d, step_max: float) -> float:
    """A constant velocity's |value|; a constant displacement or force does not move."""
    return abs(d.value) if d.kind == "velocity" else 0.0


def ramp_speed(p: str, d, step_max: float) -> float:
    """A ramp: the velocity's final |value|, or a displacement's |value| / duration."""
    _duration(p, d)
    return abs(d.value) if d.kind == "velocity" else abs(d.value) / d.duration


def half_sine_speed(p: str, d, step_max: float) -> float:
    """A half-sine: the velocity's |amplitude|, or a displacement's pi |amplitude| / duration."""
    _duration(p, d)
    return abs(d.amplitude) * (1.0 if d.kind == "velocity" else math.pi / d.duration)


def harmonic_speed(p: str, d, step_max: float) -> float:
    """A harmonic (its frequency resolved by the steps): |value| + |amplitude| of a velocity,
    2 pi f |amplitude| of a displacement."""
    _frequency_in_range(f"{p}.frequency", d.frequency, step_max)
    if d.kind == "velocity":
        return abs(d.value) + abs(d.amplitude)
    return 2.0 * math.pi * d.frequency * abs(d.amplitude)


def chirp_speed(p: str, d, step_max: float) -> float:
    """A chirp (a displacement or a force; both frequencies resolved by the steps): its
    largest speed 2 pi |amplitude| (f_top + |f1 - f0| / 2)."""
    _duration(p, d)
    if d.kind == "velocity":
        raise ScenarioError(
            f"{p}.kind",
            d.kind,
            "a chirp prescribes a displacement or a force (its velocity's integral, a Fresnel "
            'integral, is not computed): use kind = "displacement"',
        )
    for name in ("frequency", "frequency_end"):
        _frequency_in_range(f"{p}.{name}", getattr(d, name), step_max)
    f_top = max(d.frequency, d.frequency_end)
    return 2.0 * math.pi * abs(d.amplitude) * (f_top + abs(d.frequency_end - d.frequency) / 2.0)


def table_speed(p: str, d, step_max: float) -> float:
    """A table's checks (two or more points, finite, times >= 0 and increasing) and the
    largest speed it asks for [m/s]."""
    t, v = d.times, d.values
    for name, xs in (("times", t), ("values", v)):
        if not isinstance(xs, tuple) or not all(is_number(x) and math.isfinite(x) for x in xs):
            raise ScenarioError(f"{p}.{name}", xs, "must be a list of finite numbers")
    if len(t) < 2 or len(t) != len(v):
        raise ScenarioError(
            f"{p}.times", list(t), f"must hold two or more times, as many as values ({len(t)} times, {len(v)} values)"
        )
    if t[0] < 0.0:
        raise ScenarioError(f"{p}.times", list(t), "must start at t >= 0 [s]")
    for a, (t0, t1) in enumerate(zip(t[:-1], t[1:])):
        if not t1 > t0:
            raise ScenarioError(
                f"{p}.times", list(t), f"must increase: times[{a + 1}] = {t1!r} is not after times[{a}] = {t0!r}"
            )
    if d.kind == "velocity":
        return max(abs(x) for x in v)
    if d.kind == "displacement":
        return max(abs(v1 - v0) / (t1 - t0) for t0, t1, v0, v1 in zip(t[:-1], t[1:], v[:-1], v[1:]))
    return 0.0


#: The drive profiles, name -> DriveProfile, in the order of their ids (physics.drives).
DRIVE_PROFILE_REGISTRY: dict[str, DriveProfile] = {
    "constant": DriveProfile("granplate.physics.profiles.constant", ("value",), constant_speed, "value"),
    "ramp": DriveProfile("granplate.physics.profiles.ramp", ("value", "duration"), ramp_speed, "value"),
    "half-sine": DriveProfile(
        "granplate.physics.profiles.half_sine", ("amplitude", "duration"), half_sine_speed, "amplitude"
    ),
    "harmonic": DriveProfile(
        "granplate.physics.profiles.harmonic", ("value", "amplitude", "frequency"), harmonic_speed, "amplitude"
    ),
    "table": DriveProfile("granplate.physics.profiles.table", ("times", "values"), table_speed, "values"),
    "chirp": DriveProfile(
        "granplate.physics.profiles.chirp",
        ("amplitude", "frequency", "frequency_end", "duration"),
        chirp_speed,
        "amplitude",
    ),
}
#: A drive's time profiles (`Drive.profile`), the registry's names.
DRIVE_PROFILES: tuple[str, ...] = tuple(DRIVE_PROFILE_REGISTRY)

"""Checks of [gravity] and [[drives]] (docs/scenario.md, sections "Gravity" and "Drives"):
each raises ScenarioError(field, value, allowed) before anything runs. The one owner of
the rules a drive's fields obey; `validate` calls `check_gravity` and `check_drives` on
the resolved scenario.
"""

from __future__ import annotations

import math
from typing import Any

from granplate.errors import ScenarioError
from granplate.setup.fields import closest_name, finite, is_number, string_in
from granplate.setup.drive_profiles import DRIVE_PROFILE_REGISTRY, DRIVE_PROFILES, PAR_FIELDS
from granplate.setup.scenario import DRIVE_KINDS, DRIVE_TARGETS, Drive, Scenario

#: the largest |g| [m/s^2] a scenario may ask for (a centrifuge's 10^5 g)
GRAVITY_MAX = 1e6
#: a drive's direction must have unit length within this
UNIT_TOL = 1e-9
#: the largest mass [kg] of a force-driven wall (a piston; a thousand tonnes)
PISTON_MASS_MAX = 1e6
#: the defaults of the fields a profile may read (a field it does not read must keep its own)
_DEFAULTS: dict[str, Any] = {**PAR_FIELDS, "times": (), "values": ()}


def granule_labels(s: Scenario) -> list[str]:
    """Each granule's label as results name it (its label, or its 1-based index)."""
    return [g.label or str(i + 1) for i, g in enumerate(s.granules)]


def check_gravity(s: Scenario) -> None:
    """[gravity] g: one finite component per dimension, |g| <= GRAVITY_MAX (the plate, the
    plane's or space's elastic solid, carries its own weight too, docs/model.md section 3.11;
    a solid no support holds against it is refused when it is built, model.body_weight)."""
    if s.gravity is None:
        return
    g = s.gravity.g
    names = "[gx, gy]" if s.dimension == 2 else "[gx, gy, gz]"
    if not isinstance(g, tuple) or len(g) != s.dimension or not all(is_number(c) and math.isfinite(c) for c in g):
        raise ScenarioError(
            "gravity.g",
            list(g) if isinstance(g, tuple) else g,
            f"must be {s.dimension} finite numbers {names} [m/s^2] (dimension = {s.dimension})",
        )
    if not math.hypot(*g) <= GRAVITY_MAX:
        raise ScenarioError("gravity.g", list(g), f"allowed |g| <= {GRAVITY_MAX:g} m/s^2")


def check_drives(s: Scenario, step_max: float, wave_speed: float) -> None:
    """Every [[drives]] entry of the resolved scenario s: its target (a known wall or
    granule, driven once), kind, direction (a unit vector; a wall's along its normal),
    profile and the fields that profile reads (and no other), the peak speed it asks for
    below `wave_speed` [m/s] (Hertz's law is quasi-static), a harmonic's period at least
    setup.drive_profiles.STEPS_PER_PERIOD steps of `step_max` [s]."""
    seen: dict[str, int] = {}
    for k, d in enumerate(s.drives):
        p = f"drives[{k}]"
        if not isinstance(d, Drive):
            raise ScenarioError(p, d, "must be a table of a drive's fields")
        kind, index = drive_target(s, p, d.target)
        if d.target in seen:
            raise ScenarioError(
                f"{p}.target", d.target, f"drives[{seen[d.target]}] drives it already; a body takes one drive"
            )
        seen[d.target] = k
        string_in(f"{p}.kind", d.kind, DRIVE_KINDS)
        direction = _unit(f"{p}.direction", d.direction, s.dimension)
        if kind == "wall":
            _wall_drive(p, d, s.walls[index], direction)
        if kind == "wall" and d.kind == "force":
            piston_mass(f"{p}.mass", d.mass)
        elif d.mass != 0.0:
            raise ScenarioError(
                f"{p}.mass", d.mass, "read by a force drive on a wall only (its piston's mass [kg]); leave it out"
            )
        string_in(f"{p}.profile", d.profile, DRIVE_PROFILES)
        _profile_fields(p, d)
        _profile_values(p, d, step_max, wave_speed)
        if not isinstance(d.label, str):
            raise ScenarioError(f"{p}.label", d.label, "must be a string")


def drive_target(s: Scenario, p: str, target: Any) -> tuple[str, int]:
    """("wall" or "granule", its index in the resolved scenario) of a drive's target
    "wall LABEL" or "granule LABEL"."""
    parts = target.split(None, 1) if isinstance(target, str) else []
    if len(parts) != 2 or parts[0] not in DRIVE_TARGETS:
        raise ScenarioError(
            f"{p}.target",
            target,
            'must be "wall LABEL" or "granule LABEL" (the label of a [[walls]] or [[granules]] entry)',
        )
    kind, label = parts[0], parts[1].strip()
    labels = [w.label for w in s.walls] if kind == "wall" else granule_labels(s)
    if label not in labels:
        near = closest_name(label, labels)
        hint = f" (did you mean '{kind} {near}'?)" if near else ""
        known = ", ".join(repr(x) for x in labels[:12]) + (", ..." if len(labels) > 12 else "")
        raise ScenarioError(
            f"{p}.target", target, f"no {kind} is labelled {label!r}{hint}; the {kind}s' labels: " + (known or "none")
        )
    return kind, labels.index(label)


def _unit(path: str, v: Any, dimension: int) -> tuple[float, ...]:
    """A direction of `dimension` finite components and unit length (within UNIT_TOL)."""
    if not isinstance(v, tuple) or len(v) != dimension or not all(is_number(c) and math.isfinite(c) for c in v):
        raise ScenarioError(
            path,
            list(v) if isinstance(v, tuple) else v,
            f"must be {dimension} finite numbers (a unit vector; dimension = {dimension})",
        )
    norm = math.hypot(*v)
    if abs(norm - 1.0) > UNIT_TOL:
        raise ScenarioError(
            path, list(v), f"must be a unit vector (|direction| = {norm:.12g}; allowed 1 within {UNIT_TOL:g})"
        )
    return v


def piston_mass(path: str, mass: Any) -> float:
    """A force-driven wall's mass [kg]: required, 0 < mass <= PISTON_MASS_MAX."""
    what = f"a force-driven wall's mass [kg] is required: allowed 0 < mass <= {PISTON_MASS_MAX:g}"
    m = finite(path, mass, what)
    if not 0.0 < m <= PISTON_MASS_MAX:
        raise ScenarioError(path, mass, what)
    return m


def _wall_drive(p: str, d: Drive, wall, direction: tuple[float, ...]) -> None:
    """A wall moves along its own normal (sliding a plane along itself would change only
    friction, which a moving wall does not carry), moved or pushed (a piston)."""
    n = [float(c) for c in wall.normal]
    norm = math.hypot(*n)
    cos = sum(a * b for a, b in zip(n, direction)) / norm
    if abs(abs(cos) - 1.0) > UNIT_TOL:
        raise ScenarioError(
            f"{p}.direction",
            list(direction),
            f"a wall moves along its normal: allowed {[c / norm for c in n]} or its opposite (wall {wall.label!r})",
        )


def _profile_fields(p: str, d: Drive) -> None:
    """The fields the profile reads are numbers of the right kind; the others keep their
    defaults (a field the profile would ignore is refused, not silently dropped)."""
    used = DRIVE_PROFILE_REGISTRY[d.profile].fields
    if d.file is not None:
        raise ScenarioError(
            f"{p}.file",
            d.file,
            "is read when the scenario is loaded from TOML (setup.io); a "
            "Drive built in Python gives times and values instead",
        )
    for name, default in _DEFAULTS.items():
        value = getattr(d, name)
        if name not in used and value != default and not (name in ("times", "values") and value == ()):
            raise ScenarioError(
                f"{p}.{name}", value, f"not read by profile {d.profile!r}, which reads " + ", ".join(used)
            )
    for name in used:
        if name in ("times", "values"):
            continue
        finite(f"{p}.{name}", getattr(d, name))


def _profile_values(p: str, d: Drive, step_max: float, wave_speed: float) -> None:
    """The profile's own rules (its registry entry's `speed`: durations and frequencies in
    range, a table's times increasing) and the peak speed the drive asks for below the wave
    speed."""
    profile = DRIVE_PROFILE_REGISTRY[d.profile]
    speed = profile.speed(p, d, step_max)  # the largest speed [m/s] a motion drive asks for
    if d.kind != "force" and not speed < wave_speed:
        field = profile.speed_field
        raise ScenarioError(
            f"{p}.{field}",
            getattr(d, field),
            f"asks for a speed of {speed:.6g} m/s; allowed "
            f"below {wave_speed:.6g} m/s, the slowest elastic wave speed sqrt(E / rho) of the "
            "materials (Hertz's law is quasi-static)",
        )

"""Checks of [[sensors]] and time.sensor_interval (docs/scenario.md, section "Sensors"):
each raises ScenarioError(field, value, allowed) before anything runs. The one owner of
the rules a sensor's fields obey; `validate` calls `check_sensors` on the resolved
scenario.
"""

from __future__ import annotations

import math

from granplate.errors import ScenarioError
from granplate.setup.drive_checks import granule_labels
from granplate.setup.fields import closest_name, finite
from granplate.setup.scenario import Scenario, Sensor

#: the most values (samples x sensors) a run's sensors may record: 2^26 float64 numbers,
#: 512 MiB in each of the loop's buffer, the Dataset and the file written.
MAX_SENSOR_VALUES = 2**26


def sensor_interval(s: Scenario) -> float:
    """The sensors' sampling interval [s]: time.sensor_interval, or time.output_interval
    where it is not given."""
    dt = s.time.sensor_interval
    return float(s.time.output_interval if dt is None else dt)


def n_sensor_samples(t_end: float, interval: float) -> int:
    """How many sample times k * interval, k = 0, 1, ..., lie in [0, t_end] [s] (a time
    within 1e-9 of an interval of t_end counts)."""
    return int(math.floor(t_end / interval + 1e-9)) + 1


def check_sensors(s: Scenario) -> None:
    """time.sensor_interval (finite, > 0, at most time.t_end) and every [[sensors]] entry
    of the resolved scenario s: its granule (a known label), its name (a string, unique
    among the sensors) and the run's samples x sensors within MAX_SENSOR_VALUES."""
    dt = s.time.sensor_interval
    if dt is not None:
        x = finite("time.sensor_interval", dt, "must be a finite number > 0 [s] (absent: time.output_interval)")
        if not x > 0.0:
            raise ScenarioError("time.sensor_interval", dt, "must be > 0 [s] (absent: time.output_interval)")
        if x > s.time.t_end:
            raise ScenarioError("time.sensor_interval", dt, f"must be <= time.t_end = {s.time.t_end!r} s")
    if not s.sensors:
        return
    if not isinstance(s.sensors, tuple):
        raise ScenarioError("sensors", s.sensors, "must be a list of [[sensors]] tables")
    labels = granule_labels(s)
    seen: dict[str, int] = {}
    for k, sensor in enumerate(s.sensors):
        p = f"sensors[{k}]"
        if not isinstance(sensor, Sensor):
            raise ScenarioError(p, sensor, "must be a table of a sensor's fields (granule, name)")
        _granule(p, sensor.granule, labels)
        if not isinstance(sensor.name, str):
            raise ScenarioError(f"{p}.name", sensor.name, "must be a string")
        if sensor.label in seen:
            where = f"{p}.name" if sensor.name else f"{p}.granule"
            raise ScenarioError(
                where,
                sensor.label,
                f"sensors[{seen[sensor.label]}] is named {sensor.label!r} already; give each sensor its own `name`",
            )
        seen[sensor.label] = k
    n = n_sensor_samples(s.time.t_end, sensor_interval(s)) * len(s.sensors)
    if n > MAX_SENSOR_VALUES:
        field = "time.sensor_interval" if dt is not None else "sensors"
        raise ScenarioError(
            field,
            dt if dt is not None else len(s.sensors),
            f"the sensors would record {n:.3g} values (samples over time.t_end = {s.time.t_end!r} s times "
            f"{len(s.sensors)} sensors), allowed at most {MAX_SENSOR_VALUES} (2^26): raise time.sensor_interval "
            "or shorten the run",
        )


def _granule(p: str, label: object, labels: list[str]) -> int:
    """The index in the resolved scenario of the granule a sensor names by its label."""
    if not isinstance(label, str):
        raise ScenarioError(
            f"{p}.granule",
            label,
            "must be a string: a granule's label (an unlabelled granule's is its 1-based index, e.g. \"3\")",
        )
    if label not in labels:
        near = closest_name(label, labels)
        hint = f" (did you mean {near!r}?)" if near else ""
        known = ", ".join(repr(x) for x in labels[:12]) + (", ..." if len(labels) > 12 else "")
        raise ScenarioError(
            f"{p}.granule", label, f"no granule is labelled {label!r}{hint}; the granules' labels: " + (known or "none")
        )
    return labels.index(label)


def sensor_granules(s: Scenario) -> list[int]:
    """Each sensor's granule as its index in the resolved scenario s (checked)."""
    labels = granule_labels(s)
    return [_granule(f"sensors[{k}]", x.granule, labels) for k, x in enumerate(s.sensors)]

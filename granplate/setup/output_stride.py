"""The output stride of a run of many granules (docs/output.md, "Output times of a large
run"): every output time holds each granule's state, so a million granules at the default
output interval would write a Dataset no one can open. A run whose granule states would
hold more than GRANULE_VALUES_MAX values (granules x output times) outputs every k-th
output time instead, k the smallest stride that keeps them within it, unless the scenario
gives its own `time.field_interval` (any value but the default), which is then the output
interval: the user's choice wins.

`output_stride(s)`: k for a resolved scenario (1: the outputs as given);
`with_output_stride(s)`: the scenario run with it (time.output_interval k times as long,
the intervals that must be whole multiples of it rounded up to them, the sensors' sample
interval kept as it was).
"""

from __future__ import annotations

import math
from dataclasses import replace

from granplate.setup.scenario import Scenario, TimeSettings

#: The most values a granule's state variable (x, vx, omega_x, ...) holds over a run's
#: output times before the outputs are strided: 25 output times of a million granules,
#: 200 MB per variable; 2,001 output times (t_end 2 ms every 1 us) of 12,000 granules.
GRANULE_VALUES_MAX = 25_000_000
#: time.field_interval at its default counts as not given [s].
DEFAULT_FIELD_INTERVAL = TimeSettings().field_interval
#: Relative tolerance of a whole multiple of the output interval.
MULTIPLE_RTOL = 1e-9


def output_count(t_end: float, interval: float) -> int:
    """Output times 0, interval, ..., t_end (solver.schedule.output_times)."""
    return int(math.ceil(t_end / interval - MULTIPLE_RTOL)) + 1


def output_stride(s: Scenario) -> int:
    """The stride k >= 1 of a resolved scenario's output times: 1 while its granules times
    its output times stay within GRANULE_VALUES_MAX; beyond, time.field_interval /
    time.output_interval when field_interval is given (not its default), else the smallest
    k that keeps them within it (k output intervals at most t_end: outputs at 0 and t_end)."""
    t, ng = s.time, len(s.granules)
    if ng * output_count(t.t_end, t.output_interval) <= GRANULE_VALUES_MAX:
        return 1
    if t.field_interval != DEFAULT_FIELD_INTERVAL:
        return max(1, round(t.field_interval / t.output_interval))
    last = output_count(t.t_end, t.output_interval) - 1  # the stride with outputs at 0 and t_end
    most = max(2, GRANULE_VALUES_MAX // ng)  # output times allowed
    k = max(1, math.ceil(t.t_end / (t.output_interval * (most - 1)) - MULTIPLE_RTOL))
    while k < last and output_count(t.t_end, k * t.output_interval) > most:
        k += 1
    return min(k, last)


def _multiple(dt: float | None, interval: float) -> float | None:
    """dt [s] rounded up to a whole multiple of interval (None and 0 kept)."""
    if dt is None or dt == 0.0:
        return dt
    return max(1, math.ceil(dt / interval - MULTIPLE_RTOL)) * interval


def with_output_stride(s: Scenario) -> Scenario:
    """The resolved scenario `s` with its output stride applied (itself for stride 1)."""
    k = output_stride(s)
    if k == 1:
        return s
    t = s.time
    out = min(k * t.output_interval, t.t_end)
    time = replace(
        t,
        output_interval=out,
        field_interval=max(1, math.ceil(max(t.field_interval, out) / out - MULTIPLE_RTOL)) * out,
        contact_interval=_multiple(t.contact_interval, out),
        restart_interval=_multiple(t.restart_interval, out),
        sensor_interval=t.output_interval if t.sensor_interval is None else t.sensor_interval,
    )
    return replace(s, time=time)

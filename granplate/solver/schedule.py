"""A run's schedule: its output times and its sensors' sample times (docs/model.md section
3.15), the steps landing on both where they coincide."""

from __future__ import annotations

import math

import numpy as np

from granplate.model.arrays import Model
from granplate.setup.sensor_checks import n_sensor_samples, sensor_granules, sensor_interval


def output_times(t_end: float, dt_out: float) -> np.ndarray:
    """Output times 0, dt_out, 2 dt_out, ..., ending exactly at t_end [s]."""
    n = int(math.ceil(t_end / dt_out - 1e-9))
    t = np.arange(n + 1) * dt_out
    t[-1] = t_end
    return t


#: a sensor's sample time within this fraction of the sensor interval of an output time
#: is that output time (one step lands on both).
SNAP_RTOL = 1e-9


def sensor_times(t_first: float, t_end: float, interval: float, times: np.ndarray) -> np.ndarray:
    """The sensors' sample times k * interval in [t_first, t_end] [s] (docs/model.md
    section 3.15), each within SNAP_RTOL intervals of an output time (`times`) taken as
    that output time, so that the steps land on both at once."""
    k = np.arange(n_sensor_samples(t_end, interval))
    ts = k * interval
    j = np.clip(np.searchsorted(times, ts), 1, len(times) - 1) if len(times) > 1 else np.zeros(len(ts), int)
    for cand in (j - 1, j):
        near = np.abs(times[cand] - ts) <= SNAP_RTOL * interval
        ts = np.where(near, times[cand], ts)
    ts = np.unique(np.minimum(ts, t_end))  # (one step lands on each: none twice)
    return ts[ts >= t_first - SNAP_RTOL * interval]


def sensor_setup(model: Model, times: np.ndarray) -> tuple[np.ndarray | None, np.ndarray | None]:
    """(the sample times from the run's first output time on, each sensor's granule) of
    the model's [[sensors]], or (None, None) without sensors."""
    s = model.scenario
    if not s.sensors:
        return None, None
    ts = sensor_times(float(times[0]), float(model.config.t_end), sensor_interval(s), times)
    return ts, np.asarray(sensor_granules(s), np.int64)

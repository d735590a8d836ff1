"""Restart from a result (docs/how-to/restart.md): the loop's state at a result's last
output time, stored in its Dataset as `restart_*` variables, and at earlier output times
(time.restart_interval) as `restart_t<k>_float` and `restart_t<k>_int`, and a run of a
scenario that goes on from one of them.

`with_restart(ds, snap, earlier)`: ds with the captured states (solver.snapshot) added:
the last, each array a variable `restart_<path>` (dots of the path as "__") on dimensions
of its own; the k-th earlier one (of the attribute `restart_times`) packed flat into two
variables `restart_t<k>_float`, `restart_t<k>_int`, whose attribute `layout` lists its
arrays' paths and shapes. `restart_times(ds)`: the times [s] a state is stored at.
`restart_state(ds, time)`: one state's arrays back, keyed by path.
`restart_source(scenario, ...)`: the result and time a run restarts from (the command
line's, or the scenario's [restart]). `check_restart(ds, scenario, time)`: refuses
(ScenarioError naming the field) a result whose granules differ from the scenario's
(count, radii, materials, dimension) or a chosen time at which no state is stored.
"""

from __future__ import annotations

import json
import re

import numpy as np
import xarray as xr

from granplate.errors import ScenarioError

PREFIX = "restart_"
#: the names of the states stored before the last: restart_t<k>_float, restart_t<k>_int
EARLIER = re.compile(r"^restart_t(\d+)_(float|int)$")


def _name(path: str) -> str:
    return PREFIX + path.replace(".", "__")


def _variables(snap: dict[str, np.ndarray]) -> dict[str, xr.DataArray]:
    """The last state: one variable per array, on dimensions of its own."""
    data = {}
    for path, a in snap.items():
        name = _name(path)
        dims = tuple(f"{name}_{k}" for k in range(a.ndim))
        data[name] = xr.DataArray(a, dims=dims, attrs={"long_name": f"restart state: {path}"})
    return data


def _packed(snap: dict[str, np.ndarray], k: int, t: float) -> dict[str, xr.DataArray]:
    """An earlier state in two flat variables, restart_t<k>_float (float64) and
    restart_t<k>_int (int64; the integer and boolean arrays), their arrays in the order
    of the attribute `layout` (JSON: [path, shape] pairs): a few variables per state keep
    the file's writing and reading fast."""
    out = {}
    for kind, dtype, keep in (("float", np.float64, "f"), ("int", np.int64, "iub")):
        paths = [p for p, a in snap.items() if a.dtype.kind in keep]
        flat = [np.asarray(snap[p], dtype).ravel() for p in paths]
        name = f"{PREFIX}t{k}_{kind}"
        out[name] = xr.DataArray(
            np.concatenate(flat) if flat else np.zeros(0, dtype),
            dims=(f"{name}_n",),
            attrs={
                "long_name": f"restart state at t = {t!r} s: its {kind} arrays, flat",
                "layout": json.dumps([[p, list(snap[p].shape)] for p in paths]),
            },
        )
    return out


def _unpacked(ds: xr.Dataset, k: int) -> dict[str, np.ndarray]:
    """The arrays of the earlier state k (`_packed`), keyed by path."""
    out = {}
    for kind in ("float", "int"):
        v = ds[f"{PREFIX}t{k}_{kind}"]
        flat, at = np.asarray(v.values), 0
        for path, shape in json.loads(v.attrs["layout"]):
            n = int(np.prod(shape, dtype=np.int64))
            out[path] = flat[at : at + n].reshape(shape).copy()
            at += n
    return out


def with_restart(ds: xr.Dataset, snap: dict[str, np.ndarray] | None, earlier=()) -> xr.Dataset:
    """ds with the loop's state at its last output time (snap; None: a run that stopped)
    and at the earlier restart times (module docstring)."""
    data: dict[str, xr.DataArray] = {}
    times = []
    for k, state in enumerate(earlier):
        times.append(float(state["st.clock"][0]))
        data.update(_packed(state, k, times[-1]))
    if snap is not None:
        data.update(_variables(snap))
        times.append(float(snap["st.clock"][0]))
    if not times:
        return ds
    out = ds.assign(data)
    if snap is not None:
        out.attrs["restart_time"] = times[-1]
    out.attrs["restart_times"] = np.array(times, float)
    return out


def restart_times(ds: xr.Dataset) -> list[float]:
    """The output times [s] at which `ds` holds the loop's state, ascending (the last one,
    `restart_time`, only for a run that finished)."""
    if "restart_times" in ds.attrs:
        return [float(t) for t in np.atleast_1d(ds.attrs["restart_times"])]
    return [float(ds.attrs["restart_time"])] if "restart_time" in ds.attrs else []


def stored_time(ds: xr.Dataset, time: float | None) -> int:
    """The index in restart_times(ds) of `time` [s] (to 1e-12 relative; None: the last),
    or -1 when no state is stored there."""
    times = restart_times(ds)
    if time is None:
        return len(times) - 1
    near = [k for k, t in enumerate(times) if np.isclose(time, t, rtol=1e-12, atol=0.0)]
    return near[0] if near else -1


def restart_state(ds: xr.Dataset, time: float | None = None) -> dict[str, np.ndarray]:
    """The captured arrays of the state stored at `time` [s] (None: the last), keyed by path."""
    k = stored_time(ds, time)
    if k < 0:
        raise KeyError(f"no restart state at t = {time!r} s")
    if not ("restart_time" in ds.attrs and k == len(restart_times(ds)) - 1):
        return _unpacked(ds, k)
    return {
        str(name)[len(PREFIX) :].replace("__", "."): np.array(ds[name].values)
        for name in ds.data_vars
        if str(name).startswith(PREFIX) and not EARLIER.match(str(name))
    }


def read_result(path: str, field: str = "restart.result") -> xr.Dataset:
    """The result netCDF file at `path`, or a ScenarioError naming `field`."""
    from granplate.results.dataset import read

    try:
        return read(path)
    except FileNotFoundError:
        raise ScenarioError(field, path, "no such file (a result netCDF file, relative to the scenario file)") from None
    except (OSError, ValueError) as e:
        raise ScenarioError(field, path, f"cannot be read as a result netCDF file: {e}") from None


def restart_source(scenario, start_from=None, start_time: float | None = None):
    """(result, time [s] or None, its field, the time's field) a run restarts from: the
    given result (the command line's --from, `simulate`'s start_from), else the scenario's
    [restart] (its file read; start_time, --from-time, overrides its time); result None:
    a run from t = 0."""
    r = scenario.restart
    if start_from is not None:
        return start_from, start_time, "from", "from_time"
    if r is None:
        if start_time is not None:
            raise ScenarioError(
                "from_time", start_time, "a restart time needs a result to restart from (--from, or [restart] result)"
            )
        return None, None, "from", "from_time"
    ds = read_result(r.result)
    if start_time is not None:
        return ds, start_time, "restart.result", "from_time"
    return ds, r.time, "restart.result", "restart.time"


def check_restart(
    ds: xr.Dataset, scenario, time: float | None = None, from_field: str = "from", time_field: str = "from_time"
) -> float:
    """Refuse a restart of `scenario` from result `ds` before anything runs: no stored
    state, a chosen time [s] at which none is stored, or granules that differ (the
    fields named from_field, time_field: the command line's, or the scenario's
    [restart]); returns the restart time [s]."""
    from granplate.results.dataset import scenario_of
    from granplate.setup.geometry import resolve
    from granplate.setup.output_stride import with_output_stride

    times = restart_times(ds)
    if not times:
        raise ScenarioError(
            from_field,
            "a result",
            "holds no restart state (a run that did not finish, or made before restarts were stored)",
        )
    k = stored_time(ds, time)
    if k < 0:
        span = f"[{float(ds.time[0])!r}, {float(ds.time[-1])!r}] s"
        listed = ", ".join(repr(t) for t in times)
        last = " (the last: its end)" if "restart_time" in ds.attrs else " (the run stopped before its end)"
        raise ScenarioError(
            time_field,
            time,
            f"not a restart time of the result; available: t = {listed} s{last}; its outputs span {span} "
            "(time.restart_interval stores earlier ones)",
        )
    t1 = times[k]
    if not t1 < scenario.time.t_end:
        raise ScenarioError("time.t_end", scenario.time.t_end, f"must exceed the restart time {t1!r} s")
    old, new = resolve(scenario_of(ds)), with_output_stride(resolve(scenario))  # as the run's model has it
    if old.dimension != new.dimension:
        raise ScenarioError("dimension", new.dimension, f"must be the result's, {old.dimension}")
    if len(old.granules) != len(new.granules):
        raise ScenarioError("granules", len(new.granules), f"granules; the result has {len(old.granules)}")
    for i, (a, b) in enumerate(zip(old.granules, new.granules)):
        for field in ("radius", "material"):
            if getattr(a, field) != getattr(b, field):
                raise ScenarioError(
                    f"granules[{i}].{field}", getattr(b, field), f"must be the result's, {getattr(a, field)!r}"
                )
    for field in ("time.output_interval", "solver.scheme"):
        sec, key = field.split(".")
        va, vb = getattr(getattr(old, sec), key), getattr(getattr(new, sec), key)
        if va != vb:
            raise ScenarioError(field, vb, f"must be the result's, {va!r} (a restart keeps it)")
    return t1

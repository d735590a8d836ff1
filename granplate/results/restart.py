"""Restart from a result (docs/how-to/restart.md): the loop's state at a result's last
output time, stored in its Dataset as `restart_*` variables, and a run of a scenario that
goes on from it.

`with_restart(ds, snap)`: ds with the captured state (solver.snapshot) added, each array
a variable `restart_<path>` (dots of the path as "__") on dimensions of its own.
`restart_state(ds)`: those arrays back, keyed by path. `check_restart(ds, scenario, time)`:
refuses (ScenarioError naming the field) a result whose granules differ from the
scenario's (count, radii, materials, dimension) or a chosen time that is not the result's
stored restart time.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from granplate.errors import ScenarioError

PREFIX = "restart_"


def _name(path: str) -> str:
    return PREFIX + path.replace(".", "__")


def with_restart(ds: xr.Dataset, snap: dict[str, np.ndarray]) -> xr.Dataset:
    """ds with the loop's state at its last output time (module docstring)."""
    data = {}
    for path, a in snap.items():
        name = _name(path)
        dims = tuple(f"{name}_{k}" for k in range(a.ndim))
        data[name] = xr.DataArray(a, dims=dims, attrs={"long_name": f"restart state: {path}"})
    out = ds.assign(data)
    out.attrs["restart_time"] = float(snap["st.clock"][0])
    return out


def restart_state(ds: xr.Dataset) -> dict[str, np.ndarray]:
    """The captured arrays of a result made by `with_restart`, keyed by path."""
    return {
        str(k)[len(PREFIX) :].replace("__", "."): np.array(ds[k].values)
        for k in ds.data_vars
        if str(k).startswith(PREFIX)
    }


def check_restart(ds: xr.Dataset, scenario, time: float | None = None) -> None:
    """Refuse a restart of `scenario` from result `ds` before anything runs: no stored
    state, a chosen time [s] other than the stored one, or granules that differ."""
    from granplate.results.dataset import scenario_of
    from granplate.setup.geometry import resolve

    if "restart_time" not in ds.attrs:
        raise ScenarioError(
            "from",
            "a result",
            "holds no restart state (a run that did not finish, or made before restarts were stored)",
        )
    t1 = float(ds.attrs["restart_time"])
    if time is not None and not np.isclose(time, t1, rtol=1e-12, atol=0.0):
        span = f"[{float(ds.time[0])!r}, {float(ds.time[-1])!r}] s"
        raise ScenarioError(
            "from_time",
            time,
            f"not a restart time of the result; available: t = {t1!r} s (its last output time; its outputs span {span})",
        )
    if not t1 < scenario.time.t_end:
        raise ScenarioError("time.t_end", scenario.time.t_end, f"must exceed the restart time {t1!r} s")
    if scenario.precompression is not None:
        raise ScenarioError(
            "precompression",
            scenario.precompression.target,
            "a precompressed run cannot be restarted yet (its energy reference is not carried across the "
            "restart); run it straight to the end time",
        )
    old, new = resolve(scenario_of(ds)), resolve(scenario)
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

"""The table of a study: one row per design, its parameters, its summary metrics and its
status, as an xarray Dataset (results.nc, units in attrs) and as CSV (results.csv).
"""

from __future__ import annotations

import csv
import json
from pathlib import Path
from typing import Any

#: Summary entries that are not metrics of the design.
NOT_METRICS: tuple[str, ...] = ("scenario", "units", "contact_pairs")
#: Status of a design without a record (not computed yet, or lost with its worker).
NOT_RUN = "not run"
#: Units of scenario fields by their last dotted-path step (the others have none in attrs).
FIELD_UNITS: dict[str, str] = {
    "q0": "N/m",
    "duration": "s",
    "length": "m",
    "y0": "m",
    "t_end": "s",
    "dt_initial": "s",
    "dt_max": "s",
    "output_interval": "s",
    "field_interval": "s",
    "sensor_interval": "s",
    "restart_interval": "s",
    "contact_interval": "s",
    "time": "s",  # restart.time
    "R1": "m",
    "R2_ratio": "1",
    "E": "Pa",
    "nu": "1",
    "rho": "kg/m^3",
    "radius": "m",
    "x": "m",
    "y": "m",
    "vx": "m/s",
    "vy": "m/s",
    "width": "m",
    "height": "m",
    "thickness": "m",
    "mu": "1",
    "nx": "1",
    "ny": "1",
    "n_modes": "1",
    "rigid_layer_width": "m",
    "column_radii": "m",
    "alpha_n": "1",
    "tangential_damping": "1",
    # in space, and the layouts' counts
    "z": "m",
    "vz": "m/s",
    "size": "m",
    "origin": "m",
    "elements": "1",
    "patch_radius": "m",
    "stress_radius": "m",
    "max_frequency": "Hz",
    "force": "N",
    "Y": "Pa",
    "k_s": "s/m",
    "count": "1",
    "cells": "1",
    "planes": "1",
    "columns": "1",
    "rows": "1",
    "intruder_ratio": "1",
    # every other number of a scenario (the generated reference of the site shows them)
    "dimension": "1",
    "taper": "1",
    "dimer_ratio": "1",
    "decorated_ratio": "1",
    "seed": "1",
    "radius_spread": "1",
    "jitter": "1",
    "vacancy_fraction": "1",
    "intruder_every": "1",
    "omega": "rad/s",
    "offset": "m",
    "point": "m",
    "lower": "m",
    "upper": "m",
    "centre": "m",
    "normal": "1",
    "direction": "1",
    "axis": "1",
    "x0": "m",
    "neighbour_gap": "1",
    "skin": "1",
    "overlap_warn": "1",
    "overlap_stop": "1",
    "overlap_start": "1",
    "radius_range": "m",
    "sizes": "m",
    "fractions": "1",
    "mean": "m",
    "std": "m",
    "container": "m",
    "settle_tolerance": "1",
    "settle_damping": "1",
    "settle_friction": "1",
    "settle_softening": "1",
    "settle_residual": "1",
    "settle_time": "s",
    "dt_min": "s",
    "lambda_target": "1",
    "iteration_rtol": "1",
    "iteration_atol": "N",
    "max_iterations": "1",
    "energy_tol": "1",
    "error_tol": "1",
    "implicit_dt_max": "s",
    "energy_span": "s",
    "threads": "1",
    "mass": "kg",
    # the measured yielding law (docs/model.md section 3.10)
    "C": "1",
    "rate_ref": "1/s",
    "hardness_ratio": "1",
    "unloading_factor": "1",
}


def field_unit(path: str) -> str | None:
    """The unit of a scenario field by dotted path ("load.q0" -> "N/m"), or None if unknown."""
    return FIELD_UNITS.get(path.rsplit(".", 1)[-1].split("[", 1)[0])


def metric_names(records: list[dict | None]) -> tuple[list[str], dict[str, str]]:
    """The metrics of the summaries (in summary order) and their units."""
    names: list[str] = []
    units: dict[str, str] = {}
    for r in records:
        if r and r.get("summary"):
            for k in r["summary"]:
                if k not in NOT_METRICS and k not in names:
                    names.append(k)
            units.update(r["summary"].get("units", {}))
    return names, units


def status_of(record: dict | None) -> str:
    return NOT_RUN if record is None else str(record["status"])


def to_dataset(
    names: tuple[str, ...], designs, keys: list[str], records: list[dict | None], attrs: dict[str, Any] | None = None
):
    """The study's Dataset, indexed by `design` (0, 1, ... in study order): one variable per
    parameter and per summary metric (NaN where a design has no value), `status` ("ok",
    the failure message, or "not run") and `key` (the design's record name)."""
    import numpy as np
    import xarray as xr

    n = len(designs)
    data: dict[str, Any] = {}
    for j, name in enumerate(names):
        values = [d[j] for d in designs]
        arr = np.array(values, dtype=object if any(isinstance(v, str) for v in values) else None)
        if arr.dtype == object:
            arr = arr.astype(str)
        unit = field_unit(name)
        data[name] = ("design", arr, {"long_name": f"parameter {name}", **({"units": unit} if unit else {})})
    metrics, units = metric_names(records)
    for m in metrics:
        values = [r["summary"].get(m) if r and r.get("summary") else None for r in records]
        if all(isinstance(v, int) and not isinstance(v, bool) for v in values):
            col = np.array(values, dtype=np.int64)  # counts stay integers when none is missing
        else:
            col = np.array([np.nan if v is None else v for v in values], dtype=float)
        data[m] = ("design", col, {"long_name": f"metric {m}", **({"units": units[m]} if m in units else {})})
    data["status"] = (
        "design",
        np.array([status_of(r) for r in records], dtype=str),
        {"long_name": '"ok", the failure message, or "not run"'},
    )
    data["key"] = ("design", np.array(keys, dtype=str), {"long_name": "record designs/KEY.json"})
    return xr.Dataset(data, coords={"design": np.arange(n)}, attrs=dict(attrs or {}))


def _cell(v: Any) -> str:
    if isinstance(v, float):
        return repr(v)
    return "" if v is None else str(v)


def write_csv(ds, path: str | Path) -> None:
    """One row per design: design, the parameters, the metrics, status, key (floats exact)."""
    import numpy as np

    cols = list(ds.data_vars)
    order = [c for c in cols if c not in ("status", "key")] + ["status", "key"]

    def write(tmp: Path) -> None:
        with open(tmp, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["design"] + order)
            for i in range(ds.sizes["design"]):
                row = [str(int(ds.design[i]))]
                for c in order:
                    v = ds[c].values[i]
                    if isinstance(v, np.floating) and np.isnan(v):
                        row.append("")
                    else:
                        row.append(_cell(v.item() if hasattr(v, "item") else v))
                w.writerow(row)

    from granplate.store import atomic_write

    atomic_write(path, write)


def write_netcdf(ds, path: str | Path) -> None:
    """The Dataset to netCDF, atomically."""
    from granplate.store import atomic_write

    atomic_write(path, lambda tmp: ds.to_netcdf(tmp))


def attrs_json(d: dict) -> str:
    return json.dumps(d, sort_keys=True)

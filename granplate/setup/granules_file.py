"""Granules as a table in a file: CSV, NPZ or netCDF, one row per granule (docs/scenario.md,
"granules_file").

A scenario's top-level `granules_file = "PATH"` (relative to the scenario file) takes the
place of its `[[granules]]` tables. Columns are named as the tables' keys, with the spin
split into components: `x, y, z, radius, material` and optionally `label, vx, vy, vz,
omega_x, omega_y, omega_z` (SI units: m, m/s, rad/s). `x, y, radius, material` are
required, the others default as in a table (0, and the label "g<i>" given by
`geometry.resolve`). In 2D (`dimension = 2`) `omega_z` is the spin about z (a table's
scalar `omega`), and `z`, `vz`, `omega_x`, `omega_y` are absent or zero.

Reading checks the shape as the TOML reader does, row by row, with the same messages: an
unknown column (the closest allowed name suggested), a required column or cell missing,
a cell of the wrong type. Rows are numbered from 1 (the first granule; in a CSV the line
after the header); a field is named "FILE, row N, column C" where a table's would be
`granules[N-1].C` (`granule_path`, which `validate` uses for the checks of values).

- CSV: a header line of column names, then one granule per line (`csv` module; an empty
  cell is a missing value).
- NPZ (`numpy.savez`): one 1-D array per column, all of one length; numbers as integers
  or floats, names as strings (no pickled objects).
- netCDF: one variable per column along one dimension (xarray); a result of granplate is
  not a granules file (see `results.seed`).

`write_granules` writes the same three formats (floats as their shortest exact text in a
CSV), so that a scenario read back from its file equals the one written.
"""

from __future__ import annotations

import contextlib
import csv
import gc
import numbers
import os
from typing import Any

import numpy as np

from granplate.errors import ScenarioError
from granplate.setup.fields import closest_name
from granplate.setup.scenario import Granule

#: The formats by file extension (lower case).
FORMATS: dict[str, str] = {".csv": "csv", ".npz": "npz", ".nc": "netcdf", ".nc4": "netcdf", ".cdf": "netcdf"}
#: Columns that every row gives (as the required keys of a [[granules]] table).
REQUIRED_COLUMNS: tuple[str, ...] = ("x", "y", "radius", "material")
#: Columns of numbers, in the order they are written.
NUMBER_COLUMNS: tuple[str, ...] = ("x", "y", "z", "radius", "vx", "vy", "vz", "omega_x", "omega_y", "omega_z")
#: Columns of strings.
STRING_COLUMNS: tuple[str, ...] = ("material", "label")
#: Every column, in the order they are written (2D: without those of COLUMNS_3D_ONLY).
COLUMNS: tuple[str, ...] = (
    "x",
    "y",
    "z",
    "radius",
    "material",
    "label",
    "vx",
    "vy",
    "vz",
    "omega_x",
    "omega_y",
    "omega_z",
)
#: Columns that are zero (or absent) in 2D.
COLUMNS_3D_ONLY: tuple[str, ...] = ("z", "vz", "omega_x", "omega_y")


def granule_path(file: str | None, index: int, field: str | None = None, dimension: int = 3) -> str:
    """How a message names granule `index` (0-based) or its `field` (a Granule field as a
    table names it: "x", "omega", "omega[1]"): `granules[i].field` for [[granules]]
    tables (file None), "FILE, row i+1, column C" for a granules file."""
    if file is None:
        return f"granules[{index}]" + ("" if field is None else f".{field}")
    row = f"{file}, row {index + 1}"
    return row if field is None else f"{row}, column {column_of(field, dimension)}"


def column_of(field: str, dimension: int) -> str:
    """The file's column of a Granule field: omega -> omega_z (2D), omega[k] -> omega_x/y/z."""
    if field == "omega":
        return "omega_z" if dimension == 2 else "omega_x"
    if field.startswith("omega["):
        return "omega_" + "xyz"[int(field[6:-1])]
    return field


def file_format(path: str) -> str:
    """ "csv", "npz" or "netcdf" from the file's extension (ScenarioError otherwise)."""
    ext = os.path.splitext(str(path))[1].lower()
    if ext not in FORMATS:
        raise ScenarioError("granules_file", str(path), "must end in " + ", ".join(FORMATS) + " (CSV, NPZ or netCDF)")
    return FORMATS[ext]


@contextlib.contextmanager
def collector_paused():
    """Python's cyclic garbage collector off while a million granules are made (they hold
    no cycles; each pass of the collector would go through all of them again: a fresh
    process read a million rows in 19 s with it, 13 s without), then as it was."""
    was = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was:
            gc.enable()


# --------------------------------------------------------------------------- reading


def _read_csv(path: str, name: str) -> dict[str, list]:
    """Columns of a CSV file as lists of strings ("" for an empty cell)."""
    with open(path, newline="", encoding="utf-8") as f:
        rows = csv.reader(f)
        header = next(rows, None)
        if not header:
            raise ScenarioError(
                "granules_file", name, "empty file: expected a header line of column names (" + ", ".join(COLUMNS) + ")"
            )
        header = [h.strip() for h in header]
        cols: list[list[str]] = [[] for _ in header]
        width = len(header)
        for n, row in enumerate(rows):
            if len(row) != width:
                if not any(c.strip() for c in row):
                    continue  # a blank line
                raise ScenarioError(
                    f"{name}, row {n + 1}",
                    row,
                    f"has {len(row)} cells; the header names {width} columns: " + ", ".join(header),
                )
            for c, cell in zip(cols, row):
                c.append(cell)
    return dict(zip(header, cols))


def _read_npz(path: str, name: str) -> dict[str, np.ndarray]:
    try:
        with np.load(path, allow_pickle=False) as z:
            return {k: z[k] for k in z.files}
    except ValueError as err:
        raise ScenarioError(
            "granules_file",
            name,
            f"not read as NPZ of plain arrays ({err}); save names as fixed-width strings, not Python objects",
        ) from None


def _read_netcdf(path: str, name: str) -> dict[str, np.ndarray]:
    import xarray as xr

    try:
        with xr.open_dataset(path) as ds:
            return {str(k): np.asarray(v.values) for k, v in ds.data_vars.items()}
    except (OSError, ValueError) as err:
        raise ScenarioError("granules_file", name, f"not read as netCDF ({err})") from None


def read_columns(path: str, name: str) -> dict[str, Any]:
    """The file's columns by name (CSV: lists of strings; NPZ, netCDF: arrays)."""
    if not os.path.isfile(path):
        raise ScenarioError("granules_file", name, "no such file")
    reader = {"csv": _read_csv, "npz": _read_npz, "netcdf": _read_netcdf}[file_format(path)]
    return reader(path, name)


def _number_column(cells: Any, col: str, name: str, required: bool) -> list[float]:
    """A column of numbers as floats, checked cell by cell as a table's number (`wrong
    type: expected a number`; an empty CSV cell: missing, or the default 0)."""
    a = cells if isinstance(cells, np.ndarray) else None
    if a is not None and a.dtype.kind in "fiu":
        return a.astype(float).tolist()
    if a is None:  # CSV text
        try:
            return np.array(cells, dtype=float).tolist()
        except ValueError:
            pass
    out = []
    for i, v in enumerate(cells.tolist() if a is not None else cells):
        path = f"{name}, row {i + 1}, column {col}"
        if isinstance(v, str) and a is None:
            if not v.strip():
                if required:
                    raise ScenarioError(path, v, f"missing required field '{path}'")
                out.append(0.0)
                continue
            try:
                out.append(float(v))
                continue
            except ValueError:
                pass
        elif isinstance(v, numbers.Real) and not isinstance(v, (bool, np.bool_)):
            out.append(float(v))
            continue
        raise ScenarioError(path, v, "wrong type: expected a number")
    return out


def _string_column(cells: Any, col: str, name: str, required: bool) -> list[str]:
    """A column of strings (an empty CSV cell: missing, or "" for a label)."""
    values = cells.tolist() if isinstance(cells, np.ndarray) else list(cells)
    if set(map(type, values)) <= {str} and not (required and "" in values):
        return values
    out = []
    for i, v in enumerate(values):
        if isinstance(v, bytes):
            v = v.decode("utf-8")
        path = f"{name}, row {i + 1}, column {col}"
        if not isinstance(v, str):
            raise ScenarioError(path, v, "wrong type: expected a string")
        if required and v == "":
            raise ScenarioError(path, v, f"missing required field '{path}'")
        out.append(v)
    return out


def _check_columns(cols: dict[str, Any], name: str) -> int:
    """Known column names, the required ones present, every column 1-D of one length;
    the number of rows."""
    allowed = list(COLUMNS)
    for k in cols:
        if k not in allowed:
            near = closest_name(k, allowed)
            hint = "" if near is None else f"did you mean '{near}'? "
            raise ScenarioError(f"{name}, column {k}", k, f"unknown column '{k}'; {hint}allowed: " + ", ".join(allowed))
    for k in REQUIRED_COLUMNS:
        if k not in cols:
            raise ScenarioError(f"{name}, column {k}", None, f"missing required column '{k}'")
    lengths = {k: (np.shape(v) if isinstance(v, np.ndarray) else (len(v),)) for k, v in cols.items()}
    for k, shape in lengths.items():
        if len(shape) != 1:
            raise ScenarioError(f"{name}, column {k}", f"shape {shape}", "must be one value per row (1-D)")
    n = lengths["x"][0]
    for k, shape in lengths.items():
        if shape[0] != n:
            raise ScenarioError(f"{name}, column {k}", f"{shape[0]} rows", f"must have as many rows as column x ({n})")
    return n


def _planar_spins(cols: dict[str, list], name: str) -> None:
    """In 2D, omega_x and omega_y are absent or zero (omega_z is the spin)."""
    for col in ("omega_x", "omega_y"):
        for i, v in enumerate(cols.get(col, ())):
            if v != 0.0:
                raise ScenarioError(
                    f"{name}, row {i + 1}, column {col}",
                    v,
                    "must be 0 in 2D (discs in the "
                    "plane spin about z: omega_z), or set dimension = 3 (spheres in space)",
                )


def read_granules(path: str, dimension: int, name: str | None = None) -> tuple[Granule, ...]:
    """The granules of the file at `path` in a scenario of `dimension` (2 or 3); `name`:
    the path as the scenario gives it, for messages. Shape errors raise ScenarioError
    naming the row and column; values are checked by `validate`."""
    name = str(path) if name is None else name
    with collector_paused():
        return _granules_of(read_columns(str(path), name), dimension, name)


def granules_of_columns(raw: dict[str, Any], dimension: int, name: str) -> tuple[Granule, ...]:
    """The granules of columns `raw` (column name -> sequence, as a file's; `name`: where
    they come from, for messages), as `read_granules` turns a file's columns into them."""
    with collector_paused():
        return _granules_of(raw, dimension, name)


def _granules_of(raw: dict[str, Any], dimension: int, name: str) -> tuple[Granule, ...]:
    """The granules of a file's columns `raw` (`read_granules`)."""
    n = _check_columns(raw, name)
    cols: dict[str, list] = {}
    for k, cells in raw.items():
        if k in STRING_COLUMNS:
            cols[k] = _string_column(cells, k, name, k in REQUIRED_COLUMNS)
        else:
            cols[k] = _number_column(cells, k, name, k in REQUIRED_COLUMNS)
    zeros = [0.0] * n
    get = lambda k: cols.get(k, zeros)
    labels = cols.get("label", [""] * n)
    if dimension == 2:
        _planar_spins(cols, name)
        spins: Any = get("omega_z")
    else:
        spins = list(zip(get("omega_x"), get("omega_y"), get("omega_z")))
    return tuple(
        map(
            Granule,
            cols["x"],
            cols["y"],
            cols["radius"],
            cols["material"],
            labels,
            get("vx"),
            get("vy"),
            spins,
            get("z"),
            get("vz"),
        )
    )


# --------------------------------------------------------------------------- writing


def granule_columns(granules: tuple[Granule, ...], dimension: int) -> dict[str, list]:
    """The columns of `granules` as written (2D: without COLUMNS_3D_ONLY; omega_z the spin)."""
    spins = [g.spin() for g in granules]
    cols: dict[str, list] = {
        "x": [g.x for g in granules],
        "y": [g.y for g in granules],
        "z": [g.z for g in granules],
        "radius": [g.radius for g in granules],
        "material": [g.material for g in granules],
        "label": [g.label for g in granules],
        "vx": [g.vx for g in granules],
        "vy": [g.vy for g in granules],
        "vz": [g.vz for g in granules],
        "omega_x": [w[0] for w in spins],
        "omega_y": [w[1] for w in spins],
        "omega_z": [w[2] for w in spins],
    }
    return {k: v for k, v in cols.items() if dimension == 3 or k not in COLUMNS_3D_ONLY}


def _csv_cell(v: Any) -> str:
    return repr(float(v)) if isinstance(v, numbers.Real) and not isinstance(v, bool) else str(v)


def write_granules(granules: tuple[Granule, ...], path: str | os.PathLike, dimension: int) -> None:
    """Write `granules` to `path` as CSV, NPZ or netCDF (by its extension), columns as
    `granule_columns`; read back by `read_granules`, the same granules."""
    path = os.fspath(path)
    fmt = file_format(path)
    cols = granule_columns(granules, dimension)
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise ScenarioError("granules_file", path, f"cannot be written: no folder {folder}")
    if fmt == "csv":
        with open(path, "w", newline="", encoding="utf-8") as f:
            w = csv.writer(f)
            w.writerow(cols)
            for row in zip(*cols.values()):
                w.writerow([_csv_cell(v) for v in row])
        return
    arrays = {k: (np.array(v, dtype=str) if k in STRING_COLUMNS else np.array(v, dtype=float)) for k, v in cols.items()}
    if fmt == "npz":
        with open(path, "wb") as f:
            np.savez(f, **arrays)
        return
    import xarray as xr

    ds = xr.Dataset({k: (("granule",), v.astype(object) if k in STRING_COLUMNS else v) for k, v in arrays.items()})
    units = {
        "material": None,
        "label": None,
        **{k: "m" for k in ("x", "y", "z", "radius")},
        **{k: "m/s" for k in ("vx", "vy", "vz")},
        **{k: "rad/s" for k in ("omega_x", "omega_y", "omega_z")},
    }
    for k in ds.data_vars:
        if units.get(k):
            ds[k].attrs["units"] = units[k]
    ds.to_netcdf(path)

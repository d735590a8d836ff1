"""Scenarios to and from TOML text and plain dicts (docs/scenario.md describes the format).

- `from_dict(d)` / `to_dict(s)`: plain dicts (TOML-shaped: tables are dicts, arrays are
  lists) <-> `Scenario`; `from_dict(to_dict(s)) == s`.
- `loads(text)` / `load(path)` / `dumps(s)` / `dump(s, path)`: TOML. Reading checks the
  *shape* (unknown keys, missing required fields, wrong types), not the physics.
- `load_scenario(name_or_path)`: a preset or a TOML file, validated (`validate`).
- `with_changes(s, {"load.q0": 1e4, "layout.R2_ratio": 0.5})`: tweak by dotted paths; the
  description then lists the changes. `parse_settings(["load.q0=3e4"])`: the same changes
  written PATH=VALUE with TOML values (the command line's `--set`).

Every error is a `ScenarioError` naming the field by its dotted path (`plate.nx`,
`granules[2].radius`, `materials.ptfe.nu`; array indices 0-based, in file order).
"""

from __future__ import annotations

import dataclasses
import functools
import numbers
import operator
import os
import re
import tomllib
import types
import typing
from typing import Any

import tomli_w

from granplate.errors import ScenarioError
from granplate.setup.fields import check_dimension, closest_name, string_in
from granplate.setup.drive_profiles import DRIVE_PROFILES
from granplate.setup.materials import LIBRARY, Material
from granplate.setup.scenario import (
    DRIVE_KINDS,
    PRECOMPRESSION_MODES,
    LAYOUT_KINDS,
    NORMAL_LAWS,
    Box,
    Contact,
    Drive,
    Granule,
    Gravity,
    Load,
    PairCoefficients,
    Plate,
    Precompression,
    Restart,
    Scenario,
    Sensor,
    Solid,
    Solver,
    TimeSettings,
    Wall,
)

#: Fields that a table must give (everything else takes the dataclass default).
REQUIRED: dict[type, tuple[str, ...]] = {
    Granule: ("x", "y", "radius", "material"),
    Wall: ("normal",),  # and offset, or (3D) point: `_walls`
    Box: ("lower", "upper"),
    PairCoefficients: ("materials",),
    Gravity: ("g",),
    Drive: ("target", "kind", "direction", "profile"),
    Precompression: ("target", "force"),
    Sensor: ("granule",),
    Restart: ("result",),
}
#: Keys of a [materials.NAME] table: E, nu, rho required; Y optional (absent: unknown);
#: the law "johnson"'s C, rate_ref, hardness_ratio, unloading_factor optional.
MATERIAL_KEYS: tuple[str, ...] = ("E", "nu", "rho", "Y", "C", "rate_ref", "hardness_ratio", "unloading_factor")
MATERIAL_REQUIRED: tuple[str, ...] = ("E", "nu", "rho")
#: String fields whose value a file must take from a fixed list, checked on reading (a
#: misspelled one is refused with the closest allowed value suggested).
CHOICES: dict[tuple[type, str], tuple[str, ...]] = {
    (Contact, "normal_law"): NORMAL_LAWS,
    (PairCoefficients, "normal_law"): NORMAL_LAWS,
    (Drive, "kind"): DRIVE_KINDS,
    (Drive, "profile"): DRIVE_PROFILES,
    (Precompression, "mode"): PRECOMPRESSION_MODES,
}
#: Fields left out of a written table when they hold this default (written, they would
#: change the text, and so the stored results' keys, of every scenario written before).
UNWRITTEN_DEFAULTS: dict[str, dict[str, Any]] = {
    "contact": {"normal_law": "hertz", "tangential_law": "tanh", "tangential_damping": 0.0},
    "layout": {"settle_softening": 1.0, "settle_residual": 1e-2, "drop": "column"},
}
#: Fields of the three-dimensional mode left out of a two-dimensional scenario's tables
#: when they hold their default, so that every 2D scenario is written as before
#: (`dimension = 2` itself is not written either).
UNWRITTEN_DEFAULTS_2D: dict[str, dict[str, Any]] = {
    "load": {"force": 0.0, "direction": [1.0, 0.0, 0.0]},
    "granules": {"z": 0.0, "vz": 0.0},
}
#: A drive's fields left out of a written [[drives]] table when they hold their default.
DRIVE_DEFAULTS: dict[str, Any] = {
    "value": 0.0,
    "amplitude": 0.0,
    "frequency": 0.0,
    "duration": 0.0,
    "frequency_end": 0.0,
    "times": [],
    "values": [],
    "label": "",
    "mass": 0.0,
}
#: [precompression]'s fields left out of its written table when they hold their default
#: (so that every precompressed scenario is written as before the held mode).
PRECOMPRESSION_DEFAULTS: dict[str, Any] = {"mass": 0.0}
#: The order of a 3D granule's keys as written (its centre, then its velocities).
GRANULE_KEYS_3D: tuple[str, ...] = ("x", "y", "z", "radius", "material", "label", "vx", "vy", "vz", "omega")


class _Missing:
    """Stands for the value of a required field that is absent."""

    def __repr__(self) -> str:
        return "<missing>"


MISSING = _Missing()


# --------------------------------------------------------------------------- dict -> Scenario


def _type_name(tp: Any) -> str:
    if tp is float:
        return "a number"
    if tp is int:
        return "an integer"
    if tp is str:
        return "a string"
    if tp is bool:
        return "true or false"
    origin = typing.get_origin(tp)
    if origin is tuple:
        args = typing.get_args(tp)
        if len(args) == 2 and args[1] is Ellipsis:
            return f"an array of {_plural(args[0])}"
        return f"an array of {len(args)} {_plural(args[0])}"
    if origin in (typing.Union, types.UnionType):
        return " or ".join(_type_name(a) for a in typing.get_args(tp) if a is not type(None))
    if dataclasses.is_dataclass(tp):
        return "a table"
    return str(tp)


def _plural(tp: Any) -> str:
    return {float: "numbers", int: "integers", str: "strings", bool: "booleans"}.get(tp, "tables")


def _convert(path: str, value: Any, tp: Any) -> Any:
    """Convert one TOML/dict value to the annotated type `tp`, or raise ScenarioError."""
    origin = typing.get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        args = typing.get_args(tp)
        if value is None and type(None) in args:
            return None
        inner = [a for a in args if a is not type(None)]
        if len(inner) == 1:
            return _convert(path, value, inner[0])
        # a number or an array (Granule.omega: a float in 2D, a 3-vector in 3D): by shape
        arrays = [a for a in inner if typing.get_origin(a) is tuple]
        scalars = [a for a in inner if typing.get_origin(a) is not tuple]
        if isinstance(value, (list, tuple)) and len(arrays) == 1:
            return _convert(path, value, arrays[0])
        if (isinstance(value, numbers.Real) and not isinstance(value, bool)) and scalars == [float]:
            return float(value)
        if isinstance(value, str) and scalars == [str]:  # a rule by name (layout.intruder_columns = "even")
            return value
        raise ScenarioError(path, value, f"wrong type: expected {_type_name(tp)}")
    if tp is float:
        if isinstance(value, numbers.Real) and not isinstance(value, bool):
            return float(value)
        raise ScenarioError(path, value, f"wrong type: expected {_type_name(tp)}")
    if tp is int:
        if isinstance(value, numbers.Integral) and not isinstance(value, bool):
            return int(value)
        raise ScenarioError(path, value, f"wrong type: expected {_type_name(tp)}")
    if tp is str:
        if isinstance(value, str):
            return value
        raise ScenarioError(path, value, f"wrong type: expected {_type_name(tp)}")
    if tp is bool:
        if isinstance(value, bool):
            return value
        raise ScenarioError(path, value, f"wrong type: expected {_type_name(tp)}")
    if origin is tuple:
        args = typing.get_args(tp)
        if not isinstance(value, (list, tuple)):
            raise ScenarioError(path, value, f"wrong type: expected {_type_name(tp)}")
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(_convert(f"{path}[{i}]", v, args[0]) for i, v in enumerate(value))
        if len(value) != len(args):
            raise ScenarioError(path, value, f"wrong length: expected {_type_name(tp)}")
        return tuple(_convert(f"{path}[{i}]", v, a) for i, (v, a) in enumerate(zip(value, args)))
    if isinstance(tp, type) and dataclasses.is_dataclass(tp):
        return _table(path, value, tp)
    raise TypeError(f"unsupported annotation {tp!r}")  # pragma: no cover


def _check_keys(path: str, d: Any, allowed: list[str]) -> None:
    """Refuse a key of table `d` (at `path`) that is not in `allowed`, suggesting the closest."""
    if not isinstance(d, dict):
        raise ScenarioError(path or "scenario", d, "wrong type: expected a table")
    for k in d:
        if k not in allowed:
            full = f"{path}.{k}" if path else str(k)
            near = closest_name(k, allowed)
            hint = "" if near is None else f"did you mean '{f'{path}.{near}' if path else near}'? "
            raise ScenarioError(full, d[k], f"unknown field '{full}'; {hint}allowed: " + ", ".join(allowed))


@functools.cache
def _fields_of(cls: type) -> tuple[dict[str, Any], list[str]]:
    """The resolved annotations and the field names of dataclass `cls` (once per class:
    resolving them costs as much as reading a table)."""
    return typing.get_type_hints(cls), [f.name for f in dataclasses.fields(cls)]


def _table(path: str, d: Any, cls: type) -> Any:
    """Build dataclass `cls` from table `d` (unknown keys refused, required ones checked)."""
    hints, names = _fields_of(cls)
    _check_keys(path, d, names)
    kwargs = {}
    required = REQUIRED.get(cls, ())
    for name in names:
        value = d.get(name)
        if value is None:  # absent (or None in a Python dict): the default
            if name in required:
                fpath = f"{path}.{name}"
                raise ScenarioError(fpath, MISSING, f"missing required field '{fpath}'")
            continue
        tp = hints[name]
        # a value of exactly its field's plain type is its own conversion (most of a table)
        kwargs[name] = value if type(value) is tp and tp in _PLAIN else _convert(f"{path}.{name}", value, tp)
        if (cls, name) in CHOICES:
            string_in(f"{path}.{name}", kwargs[name], CHOICES[cls, name])
    return cls(**kwargs)


#: Types whose values `_convert` returns unchanged (when of exactly that type).
_PLAIN: frozenset[type] = frozenset({float, int, str, bool})


def _materials(d: Any) -> dict[str, Material]:
    """The library updated by the [materials.NAME] tables of `d`."""
    if not isinstance(d, dict):
        raise ScenarioError("materials", d, "wrong type: expected a table of [materials.NAME] tables")
    out = dict(LIBRARY)
    for name, t in d.items():
        p = f"materials.{name}"
        if not isinstance(t, dict):
            raise ScenarioError(p, t, "wrong type: expected a table with E, nu, rho (and optionally Y)")
        _check_keys(p, t, list(MATERIAL_KEYS))
        vals = {}
        for k in MATERIAL_KEYS:
            if t.get(k) is None:
                if k in MATERIAL_REQUIRED:
                    raise ScenarioError(f"{p}.{k}", MISSING, f"missing required field '{p}.{k}'")
                continue
            vals[k] = _convert(f"{p}.{k}", t[k], float)
        out[str(name)] = Material(str(name), **vals)
    return out


_TOP_TABLES: dict[str, type] = {
    "plate": Plate,
    "load": Load,
    "contact": Contact,
    "time": TimeSettings,
    "solver": Solver,
    "box": Box,
    "gravity": Gravity,
    "precompression": Precompression,
    "restart": Restart,
}


def _walls(value: Any, dimension: Any) -> tuple[Wall, ...]:
    """The [[walls]] tables; each gives `offset` or (3D) `point` (or both)."""
    walls = _convert("walls", value, tuple[Wall, ...])
    for i, w in enumerate(walls):
        if w.offset is None and w.point is None:
            alt = f" (or 'walls[{i}].point' in 3D)" if dimension == 3 else ""
            raise ScenarioError(f"walls[{i}].offset", MISSING, f"missing required field 'walls[{i}].offset'{alt}")
    return walls


def _drives(value: Any, base: str | os.PathLike | None) -> tuple[Drive, ...]:
    """The [[drives]] tables; a table given as a CSV `file` (relative to the scenario's
    folder, `base`) is read into times and values."""
    drives = _convert("drives", value, tuple[Drive, ...])
    return tuple(_drive_table_file(f"drives[{k}]", d, base) if d.file is not None else d for k, d in enumerate(drives))


def _drive_table_file(path: str, d: Drive, base: str | os.PathLike | None) -> Drive:
    """`d` with its `file` (two columns: time [s], value; a header line allowed) read into
    times and values."""
    if d.times or d.values:
        raise ScenarioError(f"{path}.file", d.file, "give either a file or times and values, not both")
    given = str(d.file)
    name = os.path.join(os.fspath(base), given) if base is not None and not os.path.isabs(given) else given
    try:
        with open(name, encoding="utf-8") as f:
            lines = [ln.strip() for ln in f if ln.strip() and not ln.lstrip().startswith("#")]
    except OSError as e:
        raise ScenarioError(f"{path}.file", d.file, f"cannot be read: {e.strerror or e}") from None
    rows = []
    for n, ln in enumerate(lines):
        cells = [c.strip() for c in ln.replace(";", ",").split(",")] if ("," in ln or ";" in ln) else ln.split()
        try:
            t, v = float(cells[0]), float(cells[1])
        except (ValueError, IndexError):
            if n == 0:  # a header
                continue
            raise ScenarioError(
                f"{path}.file", d.file, f"line {n + 1} ({ln!r}) is not two numbers: time, value"
            ) from None
        rows.append((t, v))
    return dataclasses.replace(d, file=None, times=tuple(t for t, _ in rows), values=tuple(v for _, v in rows))


def _no_scalar_omega(granules: Any) -> None:
    """A 3D file's granules give omega as a vector [wx, wy, wz] (or not at all)."""
    for i, g in enumerate(granules if isinstance(granules, list) else ()):
        if isinstance(g, dict) and isinstance(g.get("omega"), numbers.Real):
            raise ScenarioError(f"granules[{i}].omega", g["omega"], "omega is a vector [wx, wy, wz] in 3D (rad/s)")


def _layout(d: Any) -> Any:
    """The [layout] table as the dataclass of its `kind` (absent kind: "paper")."""
    if not isinstance(d, dict):
        raise ScenarioError("layout", d, "wrong type: expected a table")
    kind = d.get("kind", "paper")
    if kind not in LAYOUT_KINDS:
        raise ScenarioError("layout.kind", kind, "must be one of " + ", ".join(repr(k) for k in LAYOUT_KINDS))
    return _table("layout", d, LAYOUT_KINDS[kind])


def _initial_step_within_max(t: TimeSettings, given: dict) -> TimeSettings:
    """A [time] table that lowers dt_max below the default dt_initial without giving
    dt_initial starts at dt_max (a first step above the largest would be refused)."""
    if "dt_initial" not in given and "dt_max" in given and 0.0 < t.dt_max < t.dt_initial:
        return dataclasses.replace(t, dt_initial=t.dt_max)
    return t


def _granules_file(d: dict, dimension: int, base: str | os.PathLike | None) -> dict[str, Any]:
    """The granules of a top-level `granules_file` (relative to `base`, the scenario file's
    folder; None: the working directory), and the file's name as given."""
    from granplate.setup.granules_file import read_granules

    name = _convert("granules_file", d["granules_file"], str)
    if d.get("granules") is not None:
        raise ScenarioError("granules_file", name, "give either [[granules]] tables or granules_file, not both")
    path = name if base is None or os.path.isabs(name) else os.path.join(base, name)
    return {"granules": read_granules(path, dimension, name), "granules_file": name}


def from_dict(d: dict, base: str | os.PathLike | None = None) -> Scenario:
    """A Scenario from a TOML-shaped dict; shape errors raise ScenarioError (no physics).

    Top-level keys: name, description, dimension, materials, layout, granules (or
    granules_file: a CSV, NPZ or netCDF file of them, setup.granules_file, relative to
    `base`, by default the working directory), walls, box, plate, load, contact, time,
    solver, gravity, drives, sensors, restart. Missing tables take the defaults (no layout, no plate, no box,
    no gravity, no drives; dimension 2; in 3D no load, `load.kind = "none"`). `base` is
    also the folder a drive's CSV `file` and a [restart]'s `result` are relative to.
    """
    names = [f.name for f in dataclasses.fields(Scenario)]
    _check_keys("", d, names)
    kw: dict[str, Any] = {}
    for key in ("name", "description"):
        if d.get(key) is not None:
            kw[key] = _convert(key, d[key], str)
    if d.get("dimension") is not None:
        kw["dimension"] = _convert("dimension", d["dimension"], int)
        check_dimension(kw["dimension"])
    if kw.get("dimension") == 3 and d.get("granules") is not None:
        _no_scalar_omega(d["granules"])
    if d.get("materials") is not None:
        kw["materials"] = _materials(d["materials"])
    if d.get("layout") is not None:
        kw["layout"] = _layout(d["layout"])
    for key, cls in _TOP_TABLES.items():
        if d.get(key) is not None:
            if key == "plate" and kw.get("dimension") == 3:
                cls = Solid  # the [plate] of a 3D scenario is an elastic solid
            kw[key] = _table(key, d[key], cls)
    if "time" in kw:
        kw["time"] = _initial_step_within_max(kw["time"], d["time"])
    if "restart" in kw and base is not None and not os.path.isabs(kw["restart"].result):
        kw["restart"] = dataclasses.replace(
            kw["restart"], result=os.path.normpath(os.path.join(base, kw["restart"].result))
        )
    if d.get("granules_file") is not None:
        kw.update(_granules_file(d, kw.get("dimension", 2), base))
    elif d.get("granules") is not None:
        kw["granules"] = _convert("granules", d["granules"], tuple[Granule, ...])
    if d.get("walls") is not None:
        kw["walls"] = _walls(d["walls"], kw.get("dimension", 2))
    if d.get("drives") is not None:
        kw["drives"] = _drives(d["drives"], base)
    if d.get("sensors") is not None:
        kw["sensors"] = _convert("sensors", d["sensors"], tuple[Sensor, ...])
    if kw.get("dimension") == 3 and d.get("load") is None:
        kw["load"] = Load(kind="none")  # the plane's default line load has no meaning in space
    if isinstance(kw.get("plate"), Solid) and "scheme" not in (d.get("solver") or {}):
        # an elastic solid in space is coupled by velocity Verlet (docs/model.md section 3.9)
        kw["solver"] = dataclasses.replace(kw.get("solver", Solver()), scheme="verlet")
    return Scenario(**kw)


# --------------------------------------------------------------------------- Scenario -> dict


def _plain(value: Any) -> Any:
    """Dataclasses -> dicts without None entries; tuples -> lists."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {
            f.name: _plain(getattr(value, f.name))
            for f in dataclasses.fields(value)
            if getattr(value, f.name) is not None
        }
    if isinstance(value, (tuple, list)):
        return [_plain(v) for v in value]
    if isinstance(value, bool) or isinstance(value, str):
        return value
    if isinstance(value, numbers.Integral):
        return int(value)
    if isinstance(value, numbers.Real):
        return float(value)
    return value


def _used_materials(s: Scenario) -> set[str]:
    used = {g.material for g in s.granules} | {w.material for w in s.walls}
    if s.box is not None:
        used.add(s.box.material)
    if s.layout is not None:
        used |= _layout_materials(s.layout)
    if s.plate is not None:
        used.add(s.plate.material)
    for p in s.contact.pairs:
        used |= set(p.materials)
    return used


def _layout_materials(layout: Any) -> set[str]:
    """Every material name a layout's fields give (fields named *material or *materials, and
    those of its tables, such as a space lattice's layers)."""
    used: set[str] = set()
    for f in dataclasses.fields(layout):
        v = getattr(layout, f.name)
        if f.name.endswith("material") and isinstance(v, str):
            used.add(v)
        elif f.name.endswith("materials") and isinstance(v, tuple):
            used |= {m for m in v if isinstance(m, str)}
        elif isinstance(v, tuple):
            for item in v:
                if dataclasses.is_dataclass(item) and not isinstance(item, type):
                    used |= _layout_materials(item)
    return used


def _layout_dict(layout: Any) -> dict:
    """[layout] as a dict; `kind` left out for the paper's packing (its default)."""
    d = _without_defaults(_plain(layout), UNWRITTEN_DEFAULTS["layout"])
    if d.get("kind") == "paper":
        del d["kind"]
    return d


def _material_dict(m: Material) -> dict[str, float]:
    d = {"E": float(m.E), "nu": float(m.nu), "rho": float(m.rho)}
    for k in MATERIAL_KEYS[3:]:
        if getattr(m, k) is not None:
            d[k] = float(getattr(m, k))
    return d


def to_dict(s: Scenario, all_materials: bool = False) -> dict:
    """A TOML-shaped dict of `s` (None values omitted, tuples as lists).

    Materials written: every one the scenario uses, plus every one that is absent from or
    differs from `materials.LIBRARY` (all of them with `all_materials=True`), so that
    `from_dict(to_dict(s)) == s` whenever `s.materials` holds the library's names.
    Empty top-level granules/walls are left out (their default), and so are the fields of
    `UNWRITTEN_DEFAULTS` that hold their default (`contact.normal_law = "hertz"`). A 2D
    scenario is written as before the 3D mode: no `dimension`, and the 3D fields of
    `UNWRITTEN_DEFAULTS_2D` left out where they hold their default.
    """
    d: dict[str, Any] = {"name": s.name, "description": s.description}
    if s.dimension != 2:
        d["dimension"] = s.dimension
    flat = UNWRITTEN_DEFAULTS_2D if s.dimension == 2 else {"granules": {"omega": 0.0}}
    used = _used_materials(s)
    mats = {
        name: _material_dict(m)
        for name, m in sorted(s.materials.items())
        if all_materials or name in used or LIBRARY.get(name) != m
    }
    if mats:
        d["materials"] = mats
    if s.layout is not None:
        d["layout"] = _layout_dict(s.layout)
    if s.granules:
        d["granules"] = [_without_defaults(g, flat.get("granules", {})) for g in _plain(s.granules)]
        if s.dimension == 3:
            d["granules"] = [{k: g[k] for k in sorted(g, key=_granule_key_rank)} for g in d["granules"]]
    if s.walls:
        d["walls"] = _plain(s.walls)
    if s.box is not None:
        d["box"] = _plain(s.box)
    if s.plate is not None:
        d["plate"] = _plain(s.plate)
    for key in ("load", "contact", "time", "solver"):
        d[key] = _without_defaults(_plain(getattr(s, key)), {**UNWRITTEN_DEFAULTS.get(key, {}), **flat.get(key, {})})
    if s.gravity is not None:  # (absent: not written, so that every scenario without it is written as before)
        d["gravity"] = _plain(s.gravity)
    if s.drives:
        d["drives"] = [_without_defaults(x, DRIVE_DEFAULTS) for x in _plain(s.drives)]
    if s.precompression is not None:
        d["precompression"] = _without_defaults(_plain(s.precompression), PRECOMPRESSION_DEFAULTS)
    if s.sensors:  # (none: not written, so that every scenario without them is written as before)
        d["sensors"] = [_without_defaults(x, {"name": ""}) for x in _plain(s.sensors)]
    if s.restart is not None:
        d["restart"] = _plain(s.restart)
    return d


def _granule_key_rank(key: str) -> int:
    return GRANULE_KEYS_3D.index(key) if key in GRANULE_KEYS_3D else len(GRANULE_KEYS_3D)


def _without_defaults(table: dict, defaults: dict[str, Any]) -> dict:
    """`table` without the entries that hold their value in `defaults`."""
    return {k: v for k, v in table.items() if not (k in defaults and v == defaults[k])}


# --------------------------------------------------------------------------- TOML


def loads(text: str, base: str | os.PathLike | None = None) -> Scenario:
    """A Scenario from TOML text (shape checked, physics not: see `validate`); base: the
    folder a `granules_file` is relative to (None: the working directory)."""
    try:
        d = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise ScenarioError("toml", _excerpt(text, e), f"TOML syntax error: {e}") from None
    return from_dict(d, base)


def _excerpt(text: str, e: tomllib.TOMLDecodeError) -> str:
    """The offending line, when tomllib's message gives one."""
    m = re.search(r"line (\d+)", str(e))
    if not m:
        return "<toml>"
    lines = text.splitlines()
    n = int(m.group(1))
    return lines[n - 1] if 1 <= n <= len(lines) else "<end of file>"


def load(path: str | os.PathLike) -> Scenario:
    """A Scenario from a TOML file (shape checked, physics not: see `validate`)."""
    try:
        with open(path, "rb") as f:
            raw = f.read()
    except FileNotFoundError:
        raise ScenarioError("file", str(path), "no such file") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as e:
        raise ScenarioError("file", str(path), f"not UTF-8 text: {e}") from None
    from granplate.setup.granules_file import collector_paused

    with collector_paused():  # [[granules]] tables: a dict and a Granule each
        try:
            d = tomllib.loads(text)
        except tomllib.TOMLDecodeError as e:
            raise ScenarioError("file", str(path), f"TOML syntax error: {e}") from None
        return from_dict(d, os.path.dirname(os.path.abspath(path)))


def dumps(s: Scenario, all_materials: bool = False) -> str:
    """`s` as TOML text (see `to_dict` for which materials are written)."""
    return tomli_w.dumps(to_dict(s, all_materials=all_materials))


def dumps_with_granules_file(
    s: Scenario, path: str | os.PathLike, base: str | os.PathLike | None = None, all_materials: bool = False
) -> str:
    """`s` as TOML text whose granules are in the file `path` (.csv, .npz or .nc, written
    here by `setup.granules_file.write_granules`), named by `granules_file` relative to
    `base` (the folder the TOML goes to; None: the working directory); reading the text
    back (from that folder) gives a scenario equal to `s`."""
    from granplate.setup.granules_file import write_granules

    write_granules(s.granules, path, s.dimension)
    d = to_dict(dataclasses.replace(s, granules=()), all_materials=all_materials)  # (a table per granule: slow)
    used = dict.fromkeys(map(operator.attrgetter("material"), s.granules))
    mats = {**d.get("materials", {}), **{m: _material_dict(s.materials[m]) for m in used if m in s.materials}}
    if mats:
        d["materials"] = dict(sorted(mats.items()))
    name = os.path.relpath(os.path.abspath(path), os.path.abspath(base) if base is not None else os.getcwd())
    head = {k: d.pop(k) for k in ("name", "description", "dimension") if k in d}
    return tomli_w.dumps({**head, "granules_file": name.replace(os.sep, "/"), **d})


def dump(s: Scenario, path: str | os.PathLike, all_materials: bool = False) -> None:
    """Write `s` as TOML to `path`."""
    with open(path, "wb") as f:
        f.write(dumps(s, all_materials=all_materials).encode("utf-8"))


def load_scenario(path_or_preset: str | os.PathLike, changes: dict[str, object] | None = None) -> Scenario:
    """A validated scenario: the preset of that name, or else the TOML file at that path,
    with `changes` (dotted path -> value, as `with_changes`) applied before it is validated.

    The scenario is returned as written (not resolved; `geometry.resolve` expands it).
    """
    from granplate.setup import presets  # local import: presets imports nothing of this module's users
    from granplate.setup.validate import validate

    key = os.fspath(path_or_preset)
    if isinstance(key, str) and key in presets.PRESETS:
        s = presets.preset(key)
    else:
        if not os.path.isfile(key):
            raise ScenarioError(
                "file", key, "no such file or preset; presets are: " + ", ".join(presets.preset_names(True))
            )
        s = load(key)
    if changes:
        s = with_changes(s, changes)
    validate(s)
    return s


# --------------------------------------------------------------------------- tweaks

_STEP = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)((?:\[\d+\])*)$")


def _split(path: str) -> list[str | int]:
    steps: list[str | int] = []
    for part in path.split("."):
        m = _STEP.match(part)
        if not m:
            raise ScenarioError(path, part, "not a dotted field path such as 'load.q0' or 'granules[2].vx'")
        steps.append(m.group(1))
        steps += [int(i) for i in re.findall(r"\[(\d+)\]", m.group(2))]
    return steps


#: What `with_changes` writes between a description and the list of changed fields.
CHANGED = "; changed: "
_CHANGE_ITEM = re.compile(r", (?=[A-Za-z_][A-Za-z0-9_.\[\]]* = )")


def _change_text(value: object) -> str:
    """A changed value as the description shows it: 1e+12, 0.6, "paper", [1, 2], removed."""
    if value is None:
        return "removed"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, numbers.Real):
        return f"{value:.6g}"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_change_text(v) for v in value) + "]"
    return str(value)


#: Top-level keys whose changes a description does not list: the name and description
#: themselves, and the numerical settings (time, solver), which a description never states
#: (the result's scenario_toml carries them), so that a shortened run of a preset keeps
#: the preset's description.
UNLISTED = ("name", "description", "time", "solver")


def describe_changes(description: str, changes: dict[str, object]) -> str:
    """`description` followed by "; changed: PATH = VALUE, ...", merged with earlier changes.

    Listed: changes to the case itself (materials, layout, granules, walls, plate, load,
    contact), not those of `UNLISTED`. A description that already ends in a list of
    changes keeps it; a path changed again shows its latest value in its first place.
    """
    listed = {k: v for k, v in changes.items() if _split(k)[0] not in UNLISTED}
    if not listed:
        return description
    head = CHANGED.lstrip("; ")
    if description.startswith(head):  # an empty description with changes listed
        base, sep, tail = "", head, description[len(head) :]
    else:
        base, sep, tail = description.partition(CHANGED)
    items: dict[str, str] = {}
    if sep:
        for item in _CHANGE_ITEM.split(tail):
            path, _, text = item.partition(" = ")
            items[path] = text
    for path, value in listed.items():
        items[path] = _change_text(value)
    return (base + CHANGED if base else head) + ", ".join(f"{k} = {v}" for k, v in items.items())


def with_changes(s: Scenario, changes: dict[str, object]) -> Scenario:
    """A copy of `s` with fields set by dotted path, e.g. {"load.q0": 1e4, "plate.ny": 80}.

    Paths are as in TOML: "layout.R2_ratio", "granules[2].vx", "materials.ptfe.E".
    A missing table on the way is created ({"plate.ny": 80} on a scenario without a plate
    adds a default plate with ny = 80); a value of None removes the key (back to its
    default; {"plate": None} removes the plate). The result is shape-checked by
    `from_dict`, not validated.

    The description says what changed in the case ("...; changed: load.q0 = 1e+12", see
    `describe_changes`; time and solver settings are not listed) unless `changes` sets
    "description" itself; the name stays unless `changes` sets "name".
    """
    d = to_dict(s, all_materials=True)
    if "description" not in changes:
        d["description"] = describe_changes(s.description, changes)
    for path, value in changes.items():
        steps = _split(path)
        node: Any = d
        for k, step in enumerate(steps[:-1]):
            nxt = steps[k + 1]
            if isinstance(step, int):
                if not isinstance(node, list) or not 0 <= step < len(node):
                    raise ScenarioError(
                        path, value, f"index [{step}] out of range ({len(node) if isinstance(node, list) else 0} items)"
                    )
                node = node[step]
                continue
            if not isinstance(node, dict):
                raise ScenarioError(path, value, f"'{step}' is inside something that is not a table")
            if node.get(step) is None:
                if isinstance(nxt, int):
                    raise ScenarioError(path, value, f"there is no array '{step}' to index")
                node[step] = {}
            node = node[step]
        last = steps[-1]
        if isinstance(last, int):
            if not isinstance(node, list) or not 0 <= last < len(node):
                raise ScenarioError(path, value, f"index [{last}] out of range")
            node[last] = _plain(value)
        elif not isinstance(node, dict):
            raise ScenarioError(path, value, "the parent is not a table")
        elif value is None:
            node.pop(last, None)
        else:
            node[last] = _plain(value)
    return from_dict(d)


# --------------------------------------------------------------------------- PATH=VALUE

#: A bare word taken as a string when it is no TOML value (--set layout.intruder_material=ptfe).
_BARE_WORD = re.compile(r"^[A-Za-z_][A-Za-z0-9_.+-]*$")


def toml_value(path: str, text: str) -> Any:
    """The value of field `path` written as a TOML literal: 3e4, 40, "steel", [1, 2], true.

    Also taken: a number TOML itself refuses (.5, 5.) and a bare word as a string (steel).
    Anything else is a ScenarioError naming the field.
    """
    try:
        table = tomllib.loads(f"value = {text}")
    except tomllib.TOMLDecodeError as e:
        try:
            return float(text)
        except ValueError:
            pass
        if _BARE_WORD.match(text):
            return text
        raise ScenarioError(path, text, f'not a TOML value (a number, "text", [1, 2], true or false): {e}') from None
    if set(table) != {"value"}:
        raise ScenarioError(path, text, 'one TOML value expected (a number, "text", [1, 2], true or false)')
    return table["value"]


def parse_settings(items: list[str] | tuple[str, ...]) -> dict[str, object]:
    """{dotted path: value} of "PATH=VALUE" texts (the command line's --set), in order (a
    path given twice keeps its last value); values are TOML literals (`toml_value`)."""
    changes: dict[str, object] = {}
    for item in items:
        path, sep, text = item.partition("=")
        path, text = path.strip(), text.strip()
        if not sep or not path:
            raise ScenarioError(
                "--set", item, 'expected PATH=VALUE, e.g. load.q0=3e4 or layout.intruder_material="steel"'
            )
        _split(path)
        changes[path] = toml_value(path, text)
    return changes


__all__ = [
    "from_dict",
    "to_dict",
    "loads",
    "load",
    "dumps",
    "dumps_with_granules_file",
    "dump",
    "load_scenario",
    "with_changes",
    "describe_changes",
    "parse_settings",
    "toml_value",
    "CHANGED",
    "UNLISTED",
    "REQUIRED",
    "CHOICES",
    "MATERIAL_KEYS",
    "MATERIAL_REQUIRED",
    "MISSING",
]

"""A study file: a base scenario, fixed changes and the parameters to vary (docs/studies.md).

    base = "ptfe-r05"            # a preset name or a scenario file
    [set]                        # fixed changes to the base, by dotted path
    "time.t_end" = 5e-4
    [parameters]                 # a list of values per field: the full grid of all lists
    "load.q0" = [2e3, 1e4, 5e4]
    "layout.R2_ratio" = [0.5, 0.75, 1.0]

A parameter's values are a list, `{range = [a, b], num = n}` (evenly spaced, `log = true`
for geometric spacing) or `{sample = "uniform" | "latin_hypercube", low, high, n, seed}`
(all sampled parameters are drawn together, as one n-point sample of their box). The
lists of a `[zip]` table vary together. The designs are the full grid of the axes: one
per list or range, one for the `[zip]` table, one for the sample, the first axis slowest.

Everything is checked before a design runs; an error is a `ScenarioError` naming the study
field and what is allowed. Every design's changes are applied to the base here, so an
unknown dotted path or a value of the wrong type is found now; a value the physics refuses
(a negative load, say) is that design's failure, recorded when it runs.
"""

from __future__ import annotations

import itertools
import math
import numbers
import os
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import granplate as gp
from granplate.errors import ScenarioError

#: Top-level keys of a study file.
STUDY_KEYS: tuple[str, ...] = ("base", "set", "parameters", "zip", "objectives", "constraints", "report")
#: Keys of a range form {range = [a, b], num = n, log = false}.
RANGE_KEYS: tuple[str, ...] = ("range", "num", "log")
#: Keys of a sample form {sample = METHOD, low, high, n, seed, log = false}.
SAMPLE_KEYS: tuple[str, ...] = ("sample", "low", "high", "n", "seed", "log")
#: Sampling methods of the sample form.
SAMPLE_METHODS: tuple[str, ...] = ("uniform", "latin_hypercube")

Value = float | int | str | bool


@dataclass(frozen=True)
class Study:
    """A parsed study: the base scenario with the fixed changes applied, and the designs.

    base_name: the preset name or the file as written in the study; raw_base: that
    scenario (validated); fixed: the [set] changes; names: the varied dotted paths, in study
    order; designs: one tuple of values per design (in the order of names); extra: the
    other top-level tables (objectives, constraints, report: used by the study report).
    """

    base_name: str
    raw_base: Any  # Scenario
    fixed: dict[str, Value]
    names: tuple[str, ...]
    designs: tuple[tuple[Value, ...], ...]
    extra: dict[str, Any]

    @property
    def base(self):
        """The base scenario with the fixed changes applied."""
        return gp.with_changes(self.raw_base, self.fixed) if self.fixed else self.raw_base

    def changes(self, i: int) -> dict[str, Value]:
        """The changes of design i to the base (fixed ones first, then the parameters)."""
        return {**self.fixed, **dict(zip(self.names, self.designs[i]))}

    def scenario(self, i: int):
        """The scenario of design i (shape-checked, not validated)."""
        return gp.with_changes(self.raw_base, self.changes(i))


# ------------------------------------------------------------------------- value forms


def _number(field: str, v: Any, what: str) -> float:
    if isinstance(v, bool) or not isinstance(v, numbers.Real) or not math.isfinite(v):
        raise ScenarioError(field, v, f"{what}: expected a finite number")
    return float(v)


def _positive_int(field: str, v: Any) -> int:
    if isinstance(v, bool) or not isinstance(v, numbers.Integral) or v < 1:
        raise ScenarioError(field, v, "expected an integer >= 1")
    return int(v)


def _check_keys(field: str, d: dict, allowed: tuple[str, ...]) -> None:
    for k in d:
        if k not in allowed:
            raise ScenarioError(f"{field}.{k}", d[k], "unknown key; allowed: " + ", ".join(allowed))


def _plain_list(field: str, values: Any) -> list[Value]:
    """A list of values (numbers, strings, booleans), not empty."""
    if not isinstance(values, list):
        raise ScenarioError(
            field,
            values,
            'expected a list of values, {range = [a, b], num = n} or {sample = "latin_hypercube", low, high, n, seed}',
        )
    if not values:
        raise ScenarioError(field, values, "empty list: give at least one value")
    for k, v in enumerate(values):
        if not isinstance(v, (numbers.Real, str, bool)):
            raise ScenarioError(f"{field}[{k}]", v, "expected a number, a string or true/false")
    return list(values)


def range_values(field: str, form: dict) -> list[float | int]:
    """{range = [a, b], num = n, log = false}: n values from a to b, both included, evenly
    spaced (geometrically with log = true: a, b > 0); integers when a, b are integers and
    every value is one."""
    _check_keys(field, form, RANGE_KEYS)
    ends = form.get("range")
    if not isinstance(ends, list) or len(ends) != 2:
        raise ScenarioError(f"{field}.range", ends, "expected [a, b], two numbers")
    a, b = (_number(f"{field}.range", e, "range end") for e in ends)
    num = _positive_int(f"{field}.num", form.get("num"))
    log = form.get("log", False)
    if not isinstance(log, bool):
        raise ScenarioError(f"{field}.log", log, "expected true or false")
    if log and not (a > 0 and b > 0):
        raise ScenarioError(f"{field}.range", ends, "log = true needs a > 0 and b > 0")
    import numpy as np

    v = np.geomspace(a, b, num) if log else np.linspace(a, b, num)
    if all(isinstance(e, int) for e in ends) and np.all(v == np.round(v)):
        return [int(x) for x in v]
    return [float(x) for x in v]


def _sample_settings(field: str, form: dict) -> tuple[str, int, int, bool, float, float]:
    _check_keys(field, form, SAMPLE_KEYS)
    method = form.get("sample")
    if method not in SAMPLE_METHODS:
        raise ScenarioError(f"{field}.sample", method, "allowed: " + ", ".join(SAMPLE_METHODS))
    low = _number(f"{field}.low", form.get("low"), "lower bound")
    high = _number(f"{field}.high", form.get("high"), "upper bound")
    if not low < high:
        raise ScenarioError(f"{field}.high", high, f"must be > low = {low!r}")
    n = _positive_int(f"{field}.n", form.get("n"))
    seed = form.get("seed")
    if isinstance(seed, bool) or not isinstance(seed, numbers.Integral) or seed < 0:
        raise ScenarioError(
            f"{field}.seed", seed, "expected an integer >= 0 (the sample is reproducible only with a seed)"
        )
    log = form.get("log", False)
    if not isinstance(log, bool):
        raise ScenarioError(f"{field}.log", log, "expected true or false")
    if log and not low > 0:
        raise ScenarioError(f"{field}.low", low, "log = true needs low > 0")
    return method, n, int(seed), log, low, high


def sample_points(method: str, n: int, d: int, seed: int):
    """An (n, d) array of points in the unit cube: independent uniform draws, or a Latin
    hypercube (scipy.stats.qmc.LatinHypercube), both reproducible from seed."""
    import numpy as np

    if method == "uniform":
        return np.random.default_rng(seed).random((n, d))
    from scipy.stats import qmc

    rng = np.random.default_rng(seed)
    try:
        sampler = qmc.LatinHypercube(d=d, rng=rng)
    except TypeError:  # SciPy < 1.15 names it seed
        sampler = qmc.LatinHypercube(d=d, seed=rng)
    return sampler.random(n)


def sample_values(forms: dict[str, dict]) -> list[tuple[float, ...]]:
    """The joint sample of the sampled parameters {field: form}: one tuple per point.

    All forms must share sample, n and seed (they are one sample of the box of bounds)."""
    settings = {f: _sample_settings(f, form) for f, form in forms.items()}
    first_field, first = next(iter(settings.items()))
    for f, s in settings.items():
        if s[:3] != first[:3]:
            raise ScenarioError(
                f,
                forms[f],
                "sampled parameters are drawn together: sample, n and "
                f"seed must be those of {first_field} ({first[0]!r}, n = {first[1]}, "
                f"seed = {first[2]})",
            )
    method, n, seed = first[:3]
    u = sample_points(method, n, len(settings), seed)
    cols = []
    for j, (_, _, _, log, low, high) in enumerate(settings.values()):
        if log:
            cols.append([math.exp(math.log(low) + x * (math.log(high) - math.log(low))) for x in u[:, j]])
        else:
            cols.append([low + x * (high - low) for x in u[:, j]])
    return [tuple(float(c[i]) for c in cols) for i in range(n)]


# ------------------------------------------------------------------------- the grid


def log_parameters(parameters: Any) -> frozenset[str]:
    """The parameters given in a range or sample form with `log = true` (drawn on log axes)."""
    if not isinstance(parameters, dict):
        return frozenset()
    return frozenset(f for f, spec in parameters.items() if isinstance(spec, dict) and spec.get("log") is True)


def axes(parameters: dict, zipped: dict) -> tuple[list[tuple[str, ...]], list[list[tuple]]]:
    """The study's axes: (fields of each axis, points of each axis), first axis slowest.

    One axis per list or range parameter (in file order), one for the [zip] table, one for
    the sampled parameters."""
    if not isinstance(parameters, dict):
        raise ScenarioError("parameters", parameters, "expected a table of dotted path = values")
    if not isinstance(zipped, dict):
        raise ScenarioError("zip", zipped, "expected a table of dotted path = list")
    fields: list[tuple[str, ...]] = []
    points: list[list[tuple]] = []
    sampled: dict[str, dict] = {}
    for field, spec in parameters.items():
        where = f"parameters.{field}"
        if isinstance(spec, dict) and "sample" in spec:
            sampled[where] = spec
        elif isinstance(spec, dict):
            fields.append((field,))
            points.append([(v,) for v in range_values(where, spec)])
        else:
            fields.append((field,))
            points.append([(v,) for v in _plain_list(where, spec)])
    if zipped:
        lists = {f: _plain_list(f"zip.{f}", v) for f, v in zipped.items()}
        n = {len(v) for v in lists.values()}
        if len(n) > 1:
            lengths = ", ".join(f"{f}: {len(v)}" for f, v in lists.items())
            raise ScenarioError("zip", lengths, "the lists of [zip] vary together: they must have the same length")
        fields.append(tuple(lists))
        points.append(list(zip(*lists.values())))
    if sampled:
        fields.append(tuple(w.split(".", 1)[1] for w in sampled))
        points.append(sample_values(sampled))
    return fields, points


def grid(fields: list[tuple[str, ...]], points: list[list[tuple]]) -> tuple[tuple[str, ...], list[tuple]]:
    """(names, designs): the full grid of the axes, one tuple of values per design."""
    names = tuple(f for group in fields for f in group)
    designs = [tuple(v for p in combo for v in p) for combo in itertools.product(*points)]
    return names, designs


# ------------------------------------------------------------------------- the file


def base_scenario(base: Any, folder: Path):
    """The validated base: a preset by name, else a scenario file (relative to folder)."""
    if not isinstance(base, str) or not base:
        raise ScenarioError(
            "base",
            base,
            "expected a preset name or a scenario file, e.g. "
            'base = "ptfe-r05"; presets: ' + ", ".join(gp.preset_names(True)),
        )
    if base in gp.preset_names(True):
        return gp.load_scenario(base)
    path = Path(base) if os.path.isabs(base) else folder / base
    if not path.is_file():
        raise ScenarioError(
            "base",
            base,
            f"no such preset or scenario file (looked for {path}); presets: " + ", ".join(gp.preset_names(True)),
        )
    try:
        return gp.load_scenario(path)
    except ScenarioError as err:
        raise ScenarioError(f"base ({base}): {err.field}", err.value, err.allowed) from None


def check_document(doc: Any, allowed: tuple[str, ...] = STUDY_KEYS) -> dict:
    """The study file's table, its top-level keys checked."""
    if not isinstance(doc, dict):
        raise ScenarioError("study", doc, "expected a table")
    for k in doc:
        if k not in allowed:
            raise ScenarioError(k, doc[k], "unknown key; allowed: " + ", ".join(allowed))
    if "base" not in doc:
        raise ScenarioError("base", None, "missing: name a preset or a scenario file")
    return doc


def base_and_fixed(doc: dict, folder: str | os.PathLike) -> tuple[Any, dict[str, Value]]:
    """(the validated base scenario, the [set] changes, checked against it)."""
    raw = base_scenario(doc["base"], Path(folder))
    fixed = doc.get("set", {})
    if not isinstance(fixed, dict):
        raise ScenarioError("set", fixed, "expected a table of dotted path = value")
    _check_changes("set", raw, fixed)
    return raw, dict(fixed)


def parse_study(doc: dict, folder: str | os.PathLike = ".") -> Study:
    """A Study from a study file's table (relative base files are found in folder)."""
    check_document(doc)
    raw, fixed = base_and_fixed(doc, folder)
    fields, points = axes(doc.get("parameters", {}), doc.get("zip", {}))
    names, designs = grid(fields, points)
    for f in names:
        if f in fixed:
            raise ScenarioError(f, "set and varied", "a field is either fixed in [set] or varied")
        if names.count(f) > 1:
            raise ScenarioError(f, "varied twice", "a field is varied once (in [parameters] or [zip])")
    from granplate.study.constraints import parse_constraints
    from granplate.study.design import metric_units
    from granplate.study.targets import parse_report_table

    parse_constraints(doc.get("constraints"), metric_units())  # used by the report
    parse_report_table(doc.get("report"), names)
    study = Study(
        str(doc["base"]),
        raw,
        fixed,
        names,
        tuple(designs),
        {k: v for k, v in doc.items() if k not in ("base", "set", "parameters", "zip")},
    )
    for i in range(len(designs)):
        try:
            study.scenario(i)
        except ScenarioError as err:
            where = f"design {i} ({', '.join(f'{n} = {v!r}' for n, v in zip(names, designs[i]))})"
            raise ScenarioError(err.field, err.value, f"{err.allowed} [in {where}]") from None
    return study


def _check_changes(table: str, base, changes: dict) -> None:
    try:
        gp.with_changes(base, changes)
    except ScenarioError as err:
        raise ScenarioError(f"{table}: {err.field}", err.value, err.allowed) from None


def read_document(path: str | os.PathLike) -> dict:
    """The table of a study's TOML file."""
    path = Path(path)
    if not path.is_file():
        raise ScenarioError("study file", str(path), "no such file")
    try:
        return tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as err:
        raise ScenarioError("study file", str(path), f"not valid TOML: {err}") from None


def with_settings(doc: dict, changes: dict[str, Value] | None) -> dict:
    """The study file's table with `changes` (the command line's --set) added to its [set]
    table, overriding the same paths there."""
    if not changes:
        return doc
    fixed = doc.get("set", {})
    if not isinstance(fixed, dict):
        raise ScenarioError("set", fixed, "expected a table of dotted path = value")
    return {**doc, "set": {**fixed, **changes}}


def load_study(path: str | os.PathLike, changes: dict[str, Value] | None = None) -> Study:
    """The Study of a TOML file (its base file, when relative, is beside it), with `changes`
    added to its [set] table (`with_settings`)."""
    return parse_study(with_settings(read_document(path), changes), Path(path).parent)

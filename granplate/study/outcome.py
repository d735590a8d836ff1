"""What a study folder holds, as one table for the report: every design (of a sweep) or
trial (of an optimisation) with its parameters, its metrics (from its record in
DIR/designs), its status and, with constraints, its feasibility.

A sweep's folder has results.nc; an optimisation's has trials.csv. Both have the study
file as it was run, DIR/study.toml (written by `granplate sweep` and `granplate
optimize`), from which the report takes the definition, the objectives, the
constraints and the [report] table.
"""

from __future__ import annotations

import csv
import json
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from granplate.errors import ScenarioError
from granplate.study import design as D
from granplate.study.spec import log_parameters
from granplate.study.constraints import Bound, is_feasible, parse_constraints, violations
from granplate.study.table import NOT_METRICS, field_unit
from granplate.study.targets import ReportTable, parse_report_table

#: The study file as run, inside a study's output folder.
STUDY_FILE = "study.toml"
#: A sweep's and an optimisation's table inside the folder.
SWEEP_TABLE = "results.nc"
SWEEP_CSV = "results.csv"
TRIALS_TABLE = "trials.csv"


@dataclass(frozen=True)
class Row:
    """One design or trial: its number, parameter values, metrics (None where it has none),
    status ("ok", the failure message, "not run"), record key and feasibility (None
    without constraints or without metrics)."""

    number: int
    params: dict[str, Any]
    metrics: dict[str, Any]
    status: str
    key: str
    feasible: bool | None = None

    @property
    def ok(self) -> bool:
        return self.status == "ok"


@dataclass
class StudyOutcome:
    """A study folder read back: kind ("sweep" or "optimization"), base, fixed changes,
    parameter names, rows, metric names and units, objectives, constraints, the [report]
    table, the study file's text ("" when the folder has none) and the parameters it
    spaces on a log scale (`log = true`)."""

    folder: Path
    kind: str
    base: str
    fixed: dict[str, Any]
    names: tuple[str, ...]
    rows: list[Row]
    metrics: list[str]
    units: dict[str, str]
    objectives: dict[str, str] = field(default_factory=dict)
    constraints: tuple[Bound, ...] = ()
    report: ReportTable = field(default_factory=ReportTable)
    study_text: str = ""
    version: str = ""
    log_parameters: frozenset[str] = frozenset()

    def unit(self, name: str) -> str:
        """The unit of a metric or parameter ("" when unknown, "1" when dimensionless)."""
        return self.units.get(name) or field_unit(name) or ""

    def values(self, name: str) -> list[Any]:
        """A parameter's values over the rows."""
        return [r.params.get(name) for r in self.rows]

    def metric(self, name: str) -> list[float]:
        """A metric over the rows, NaN where a row has none."""
        return [_float(r.metrics.get(name)) for r in self.rows]


def _float(v: Any) -> float:
    try:
        x = float(v)
    except (TypeError, ValueError):
        return math.nan
    return x if math.isfinite(x) else math.nan


def _value(text: str) -> Any:
    """A CSV cell back to a value: int, float or the string itself."""
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return {"True": True, "False": False}.get(text, text)


def read_study_file(folder: Path) -> tuple[dict, str]:
    """(the study file's table, its text) of DIR/study.toml; ({}, "") without one."""
    path = folder / STUDY_FILE
    if not path.is_file():
        return {}, ""
    text = path.read_text()
    try:
        return tomllib.loads(text), text
    except tomllib.TOMLDecodeError as err:
        raise ScenarioError(str(path), "study file", f"not valid TOML: {err}") from None


def _summary(folder: Path, key: str) -> dict[str, Any]:
    record = D.read_record(folder, key) if key else None
    return dict(record.get("summary") or {}) if record else {}


def _metrics_of(summaries: list[dict]) -> tuple[list[str], dict[str, str]]:
    names: list[str] = []
    units: dict[str, str] = {}
    for s in summaries:
        for k in s:
            if k not in NOT_METRICS and k not in names:
                names.append(k)
        units.update(s.get("units", {}))
    return names, units


def _sweep_outcome(
    folder: Path,
    doc: dict,
    names: tuple[str, ...],
    numbers: list[int],
    params: list[dict[str, Any]],
    table: list[dict[str, Any]],
    statuses: list[str],
    keys: list[str],
    units: dict[str, str],
    base: str,
    fixed: dict,
    version: str,
) -> StudyOutcome:
    """A sweep's outcome from its table's columns: each design's metrics from its record in
    DIR/designs, else (a folder kept without its records) the table's own values."""
    summaries = []
    for k, status, values in zip(keys, statuses, table):
        s = _summary(folder, k)
        if not s and status == "ok":  # its record is not here: the table's values
            s = {m: v for m, v in values.items() if v is not None}
        summaries.append(s)
    metrics, metric_units = _metrics_of(summaries)
    rows = [
        Row(numbers[i], params[i], {m: summaries[i].get(m) for m in metrics}, statuses[i], keys[i])
        for i in range(len(keys))
    ]
    return StudyOutcome(folder, "sweep", base, fixed, names, rows, metrics, {**metric_units, **units}, version=version)


def _read_sweep(folder: Path, doc: dict) -> StudyOutcome:
    import numpy as np
    import xarray as xr

    with xr.open_dataset(folder / SWEEP_TABLE) as ds:
        ds = ds.load()
    names = tuple(json.loads(ds.attrs.get("parameters", "[]")))
    keys = [str(k) for k in ds["key"].values]
    columns = [v for v in ds.data_vars if v not in names and v not in ("status", "key")]
    n = ds.sizes["design"]
    table = [
        {m: (None if isinstance(v := ds[m].values[i].item(), float) and np.isnan(v) else v) for m in columns}
        for i in range(n)
    ]
    units = {n_: ds[n_].attrs["units"] for n_ in names if "units" in ds[n_].attrs}
    return _sweep_outcome(
        folder,
        doc,
        names,
        [int(d) for d in ds["design"].values],
        [{n_: ds[n_].values[i].item() for n_ in names} for i in range(n)],
        table,
        [str(s) for s in ds["status"].values],
        keys,
        units,
        str(ds.attrs.get("base", doc.get("base", ""))),
        json.loads(ds.attrs.get("fixed", "{}")),
        str(ds.attrs.get("granplate_version", "")),
    )


def _read_sweep_csv(folder: Path, doc: dict) -> StudyOutcome:
    """A sweep kept as its CSV table alone (results.csv: a worked study in the docs, whose
    records and results.nc are not kept)."""
    with open(folder / SWEEP_CSV, newline="") as fh:
        table = list(csv.reader(fh))
    if not table:
        raise ScenarioError(str(folder / SWEEP_CSV), "empty", "no header: rerun granplate sweep")
    header, body = table[0], table[1:]
    known = D.metric_units()
    end = next((j for j, h in enumerate(header) if h in known or h in ("status", "key")), len(header))
    names = tuple(header[1:end])
    col = {h: j for j, h in enumerate(header)}
    metrics = [h for h in header[end:] if h not in ("status", "key")]
    units = {n: u for n in names if (u := field_unit(n))}
    return _sweep_outcome(
        folder,
        doc,
        names,
        [int(r[0]) for r in body],
        [{n: _value(r[col[n]]) for n in names} for r in body],
        [{m: (_value(r[col[m]]) if r[col[m]] != "" else None) for m in metrics} for r in body],
        [r[col["status"]] for r in body],
        [r[col["key"]] for r in body],
        units,
        str(doc.get("base", "")),
        dict(doc.get("set", {})),
        "",
    )


def _read_live_sweep(folder: Path, doc: dict) -> StudyOutcome:
    """A sweep while it runs: its designs from the study file, each design's status from its
    record in DIR/designs as it arrives ("not run" until then); no table is needed."""
    from granplate.study.spec import parse_study
    from granplate.study.table import status_of
    import granplate as gp

    study = parse_study(doc, folder)
    keys = [D.design_key(gp.dumps(study.scenario(i))) for i in range(len(study.designs))]
    records = [D.read_record(folder, k) for k in keys]
    units = {n: u for n in study.names if (u := field_unit(n))}
    return _sweep_outcome(
        folder,
        doc,
        tuple(study.names),
        list(range(len(keys))),
        [dict(zip(study.names, d)) for d in study.designs],
        [{} for _ in keys],
        [status_of(r) for r in records],
        keys,
        units,
        study.base_name,
        dict(study.fixed),
        "",
    )


def _read_trials(folder: Path, doc: dict) -> StudyOutcome:
    with open(folder / TRIALS_TABLE, newline="") as fh:
        table = list(csv.reader(fh))
    if not table:
        raise ScenarioError(str(folder / TRIALS_TABLE), "empty", "no header: rerun granplate optimize")
    header, body = table[0], table[1:]
    known = D.metric_units()
    end = next((j for j, h in enumerate(header) if h in known or h in ("feasible", "status")), len(header))
    names = tuple(header[2:end])
    col = {h: j for j, h in enumerate(header)}
    keys = [r[col["key"]] if "key" in col else "" for r in body]
    summaries = []
    for r, k in zip(body, keys):
        s = _summary(folder, k)
        if r[col["state"]] == "COMPLETE" and not s:  # told, but its record is not here
            s = {m: _value(r[col[m]]) for m in header[end:] if m in known and r[col[m]] != ""}
        summaries.append(s)
    metrics, units = _metrics_of(summaries)
    rows = []
    for r, k, s in zip(body, keys, summaries):
        state = r[col["state"]]
        status = r[col["status"]] or ("not run" if state != "COMPLETE" else "ok")
        feasible = {"yes": True, "no": False}.get(r[col["feasible"]]) if "feasible" in col else None
        rows.append(
            Row(
                int(r[0]),
                {n: _value(r[col[n]]) for n in names if r[col[n]] != ""},
                {m: s.get(m) for m in metrics} if s else {},
                status,
                k,
                feasible,
            )
        )
    fixed = dict(doc.get("set", {}))
    return StudyOutcome(folder, "optimization", str(doc.get("base", "")), fixed, names, rows, metrics, units)


def _read_table(folder: Path, doc: dict) -> StudyOutcome:
    """The study from its table: trials.csv, results.nc or results.csv."""
    if (folder / TRIALS_TABLE).is_file():
        return _read_trials(folder, doc)
    if (folder / SWEEP_TABLE).is_file():
        return _read_sweep(folder, doc)
    if (folder / SWEEP_CSV).is_file():
        return _read_sweep_csv(folder, doc)
    raise ScenarioError(
        "study folder",
        str(folder),
        f"no {SWEEP_TABLE} (granplate sweep) nor {TRIALS_TABLE} (granplate optimize): run a study into it first",
    )


def read_outcome(folder: str | Path, live: bool = False) -> StudyOutcome:
    """The study in `folder` (an optimisation when it has trials.csv, else a sweep: its
    results.nc, else its results.csv). live: a sweep read from its study file and the
    records that have arrived (while it runs: `granplate study report --watch`)."""
    folder = Path(folder)
    doc, text = read_study_file(folder)
    out = None
    if live and doc and not (folder / TRIALS_TABLE).is_file():
        try:
            out = _read_live_sweep(folder, doc)
        except ScenarioError:  # not a sweep's file (an optimisation's), or its base is elsewhere
            out = None
    out = out or _read_table(folder, doc)
    units = D.metric_units()
    out.units = {**units, **out.units}
    out.objectives = {k: str(v) for k, v in (doc.get("objectives") or {}).items()}
    out.constraints = parse_constraints(doc.get("constraints"), units)
    out.report = parse_report_table(doc.get("report"), out.names)
    out.study_text = text
    out.log_parameters = log_parameters(doc.get("parameters"))
    if out.constraints:  # a sweep's designs are judged here; a trial's verdict is Optuna's
        out.rows = [
            r
            if r.feasible is not None or not r.metrics
            else Row(
                r.number,
                r.params,
                r.metrics,
                r.status,
                r.key,
                is_feasible(violations(out.constraints, r.metrics)) if r.ok else None,
            )
            for r in out.rows
        ]
    if not out.version:
        out.version = next(
            (str(rec["granplate_version"]) for r in out.rows if r.key and (rec := D.read_record(folder, r.key))), ""
        )
    return out

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


def _read_sweep(folder: Path, doc: dict) -> StudyOutcome:
    import xarray as xr

    with xr.open_dataset(folder / SWEEP_TABLE) as ds:
        ds = ds.load()
    names = tuple(json.loads(ds.attrs.get("parameters", "[]")))
    keys = [str(k) for k in ds["key"].values]
    summaries = [_summary(folder, k) for k in keys]
    metrics, units = _metrics_of(summaries)
    for n in names:
        if "units" in ds[n].attrs:
            units[n] = ds[n].attrs["units"]
    rows = []
    for i in range(ds.sizes["design"]):
        params = {n: ds[n].values[i].item() for n in names}
        rows.append(Row(int(ds["design"].values[i]), params,
                        {m: summaries[i].get(m) for m in metrics}, str(ds["status"].values[i]), keys[i]))
    return StudyOutcome(folder, "sweep", str(ds.attrs.get("base", doc.get("base", ""))),
                        json.loads(ds.attrs.get("fixed", "{}")), names, rows, metrics, units,
                        version=str(ds.attrs.get("granplate_version", "")))


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
        rows.append(Row(int(r[0]), {n: _value(r[col[n]]) for n in names if r[col[n]] != ""},
                        {m: s.get(m) for m in metrics} if s else {}, status, k, feasible))
    fixed = dict(doc.get("set", {}))
    return StudyOutcome(folder, "optimization", str(doc.get("base", "")), fixed, names, rows,
                        metrics, units)


def read_outcome(folder: str | Path) -> StudyOutcome:
    """The study in `folder` (an optimisation when it has trials.csv, else a sweep)."""
    folder = Path(folder)
    doc, text = read_study_file(folder)
    if (folder / TRIALS_TABLE).is_file():
        out = _read_trials(folder, doc)
    elif (folder / SWEEP_TABLE).is_file():
        out = _read_sweep(folder, doc)
    else:
        raise ScenarioError("study folder", str(folder), f"no {SWEEP_TABLE} (granplate sweep) nor "
                            f"{TRIALS_TABLE} (granplate optimize): run a study into it first")
    units = D.metric_units()
    out.units = {**units, **out.units}
    out.objectives = {k: str(v) for k, v in (doc.get("objectives") or {}).items()}
    out.constraints = parse_constraints(doc.get("constraints"), units)
    out.report = parse_report_table(doc.get("report"), out.names)
    out.study_text = text
    out.log_parameters = log_parameters(doc.get("parameters"))
    if out.constraints:  # a sweep's designs are judged here; a trial's verdict is Optuna's
        out.rows = [r if r.feasible is not None or not r.metrics else
                    Row(r.number, r.params, r.metrics, r.status, r.key,
                        is_feasible(violations(out.constraints, r.metrics)) if r.ok else None)
                    for r in out.rows]
    if not out.version:
        out.version = next((str(rec["granplate_version"]) for r in out.rows
                            if r.key and (rec := D.read_record(folder, r.key))), "")
    return out

"""The [report] table of a study file: a written conclusion and the reference values the
designs are judged against (docs/studies.md).

    [report]
    conclusion = "What the study shows, in words (shown on the report page)."
    [[report.targets]]
    label = "steel-r1: max von Mises ~80 MPa (paper Fig. 3b)"
    metric = ["max_von_mises", "max_von_mises_nodes"]   # one metric, or alternatives
    value = 8e7                                         # in the metric's unit
    within = 0.2                                        # relative tolerance
    where = {"layout.intruder_material" = "steel"}      # the designs it applies to

The designs are grouped by the *choices*: the parameters that no target's `where`
names (nor zipped with one it names). Within a group, a target takes the design that matches its `where` and holds when
|v / value - 1| <= within for its metric (for one of the alternatives, when several are
given: e.g. two ways to sample the same quantity). A group meets the targets when every
target holds: `judge` returns one row per group.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from typing import Any

from granplate.errors import ScenarioError

#: Keys of the [report] table and of one target.
REPORT_KEYS: tuple[str, ...] = ("conclusion", "targets")
TARGET_KEYS: tuple[str, ...] = ("label", "metric", "value", "within", "where")


@dataclass(frozen=True)
class Target:
    """A reference value of a metric (or of one of alternative metrics) [metric's unit],
    its relative tolerance and the parameter values of the designs it applies to."""

    label: str
    metrics: tuple[str, ...]
    value: float
    within: float
    where: tuple[tuple[str, Any], ...] = ()

    def matches(self, params: dict[str, Any]) -> bool:
        """Whether a design with these parameter values is one the target applies to."""
        return all(_same(params.get(k), v) for k, v in self.where)

    def holds(self, v: float | None) -> bool | None:
        """|v / value - 1| <= within (None without a finite v)."""
        if v is None or not math.isfinite(v):
            return None
        return abs(v / self.value - 1.0) <= self.within


@dataclass(frozen=True)
class ReportTable:
    """The study's [report] table: the written conclusion and the targets."""

    conclusion: str = ""
    targets: tuple[Target, ...] = ()


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, numbers.Real) and isinstance(b, numbers.Real) and not isinstance(a, bool):
        return math.isclose(float(a), float(b), rel_tol=1e-12, abs_tol=0.0)
    return str(a) == str(b)


def _target(k: int, t: Any, units: dict[str, str], names: tuple[str, ...] | None) -> Target:
    where = f"report.targets[{k}]"
    if not isinstance(t, dict):
        raise ScenarioError(where, t, "expected a table {label, metric, value, within, where}")
    for key in t:
        if key not in TARGET_KEYS:
            raise ScenarioError(f"{where}.{key}", t[key], "unknown key; allowed: " + ", ".join(TARGET_KEYS))
    metric = t.get("metric")
    metrics = tuple(metric) if isinstance(metric, list) else (metric,)
    if not metrics or any(m not in units for m in metrics):
        raise ScenarioError(
            f"{where}.metric", metric, "expected a metric or a list of metrics; allowed: " + ", ".join(units)
        )
    value, within = t.get("value"), t.get("within", 0.1)
    for key, v in (("value", value), ("within", within)):
        if isinstance(v, bool) or not isinstance(v, numbers.Real) or not math.isfinite(v) or v == 0:
            raise ScenarioError(f"{where}.{key}", v, "expected a finite number, not 0")
    if within < 0:
        raise ScenarioError(f"{where}.within", within, "expected a relative tolerance > 0")
    match = t.get("where", {})
    if not isinstance(match, dict):
        raise ScenarioError(f"{where}.where", match, "expected a table of parameter = value")
    for field in match:
        if names is not None and field not in names:
            raise ScenarioError(
                f"{where}.where.{field}", match[field], "not a parameter of the study; parameters: " + ", ".join(names)
            )
    label = t.get("label", " or ".join(metrics))
    if not isinstance(label, str):
        raise ScenarioError(f"{where}.label", label, "expected a string")
    return Target(label, metrics, float(value), float(within), tuple(match.items()))


def parse_report_table(table: Any, names: tuple[str, ...] | None = None) -> ReportTable:
    """The [report] table, checked (names: the study's parameters, for `where`)."""
    from granplate.study.design import metric_units

    if table is None:
        return ReportTable()
    if not isinstance(table, dict):
        raise ScenarioError("report", table, "expected a table with conclusion and [[report.targets]]")
    for key in table:
        if key not in REPORT_KEYS:
            raise ScenarioError(f"report.{key}", table[key], "unknown key; allowed: " + ", ".join(REPORT_KEYS))
    conclusion = table.get("conclusion", "")
    if not isinstance(conclusion, str):
        raise ScenarioError("report.conclusion", conclusion, "expected a string")
    targets = table.get("targets", [])
    if not isinstance(targets, list):
        raise ScenarioError("report.targets", targets, "expected an array of tables [[report.targets]]")
    units = metric_units()
    return ReportTable(conclusion.strip(), tuple(_target(k, t, units, names) for k, t in enumerate(targets)))


@dataclass(frozen=True)
class Verdict:
    """One target in one group: the design it took (None: no design matches), the metric
    of the alternatives that came closest, its value and whether it holds."""

    design: int | None
    metric: str
    value: float | None
    holds: bool | None


def _verdict(target: Target, rows: list[tuple[int, dict[str, Any], dict[str, Any]]]) -> Verdict:
    for i, params, values in rows:
        if target.matches(params):
            best = None
            for m in target.metrics:
                v = values.get(m)
                v = float(v) if isinstance(v, numbers.Real) and math.isfinite(v) else None
                h = target.holds(v)
                key = (h is True, -abs(v / target.value - 1.0) if v is not None else -math.inf)
                if best is None or key > best[0]:
                    best = (key, Verdict(i, m, v, h))
            return best[1]
    return Verdict(None, target.metrics[0], None, None)


def choices(targets: tuple[Target, ...], names: tuple[str, ...], designs: list[dict[str, Any]] = ()) -> tuple[str, ...]:
    """The parameters no target's `where` names, nor follow from those it names (a
    parameter zipped with them): what a group of designs shares."""
    named = [k for t in targets for k, _ in t.where]
    named = list(dict.fromkeys(named))

    def tied(n: str) -> bool:
        seen: dict[tuple, str] = {}
        for p in designs:
            k = tuple(str(p.get(m)) for m in named)
            if seen.setdefault(k, str(p.get(n))) != str(p.get(n)):
                return False
        return bool(named) and bool(designs)

    return tuple(n for n in names if n not in named and not tied(n))


def judge(
    targets: tuple[Target, ...], names: tuple[str, ...], designs: list[dict[str, Any]], values: list[dict[str, Any]]
) -> list[tuple[dict[str, Any], list[Verdict]]]:
    """One row per group of designs sharing the choice parameters (in design order):
    (the choices' values, one Verdict per target). designs[i]: design i's parameter
    values; values[i]: its metrics (None where it has none)."""
    keep = choices(targets, names, designs)
    groups: dict[tuple, list[tuple[int, dict, dict]]] = {}
    for i, (p, v) in enumerate(zip(designs, values)):
        groups.setdefault(tuple(str(p.get(n)) for n in keep), []).append((i, p, v))
    out = []
    for rows in groups.values():
        first = rows[0][1]
        out.append(({n: first.get(n) for n in keep}, [_verdict(t, rows) for t in targets]))
    return out

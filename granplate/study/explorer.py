"""The study's interactive page, DIR/report.html: the answer first (the conclusion, the
best design of each objective drawn, a large Pareto front or the main heat map), then
views to explore (parallel coordinates from the parameters to the objectives, each metric
against each parameter, heat maps, a sortable table), every view linked: hover names a
design's parameters and metrics with units, a click opens its panel, a selection in one
view filters the others (docs/studies.md, "The report").

The page works offline: plotly.js and the page's own script and style are files in
DIR/report_assets/ beside it (`copy_assets`), the study's designs are one JSON blob in the
page (`explorer_data`), the figures' JSON is built here (`explorer_figures`) and the PNG
figures of the chosen designs are linked from DIR/report/. Above `SCATTERGL_ABOVE`
designs the scatter plots are WebGL (`scattergl`).

    >>> from granplate.study.explorer import write_explorer
    >>> write_explorer(read_outcome("q0-r2"), {})        # -> q0-r2/report.html
"""

from __future__ import annotations

import html
import itertools
import json
import math
import shutil
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

import granplate as gp
from granplate.study import design as D
from granplate.study import plots as P
from granplate.study.outcome import StudyOutcome

#: The page's assets folder beside it, and what it holds.
ASSETS = "report_assets"
PLOTLY_JS = "plotly.min.js"
PLOTLY_NOTE = "plotly.LICENSE.txt"
OWN_ASSETS: tuple[str, ...] = ("explorer.js", "explorer.css")
#: Above this many designs the scatter plots are drawn with WebGL.
SCATTERGL_ABOVE = 1000
#: Seconds between two reloads of a page written while its study runs (`live`).
REFRESH_S = 10
#: Most panels of the metric-against-parameter view, one per varied parameter.
MAX_PARAMETER_PANELS = 8
#: Significant digits of the values drawn (the data blob keeps them exact).
DRAWN_DIGITS = 7
#: Colours of the page's views: designs, the Pareto front, infeasible designs, best designs.
COLOURS = {"design": "#4c78a8", "front": "#d62728", "infeasible": "#9e9e9e"}
#: Colour and marker of the best design of each objective, in the objectives' order.
BEST_MARKERS: tuple[tuple[str, str], ...] = (
    ("#ff7f0e", "star"),
    ("#2ca02c", "diamond"),
    ("#9467bd", "square"),
    ("#8c564b", "triangle-up"),
)


# ------------------------------------------------------------------------- data


def _plain(v: Any) -> Any:
    """A value for JSON: numbers as they are (NaN and inf: None), text as text."""
    if v is None or isinstance(v, (bool, str)):
        return v
    if isinstance(v, (int, np.integer)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        return float(v) if math.isfinite(v) else None
    return str(v)


def _drawn(v: Any, factor: float = 1.0) -> Any:
    """A value in the unit drawn, to DRAWN_DIGITS digits (None: no value)."""
    v = _plain(v)
    if v is None or isinstance(v, (bool, str)):
        return v
    return float(f"{v * factor:.{DRAWN_DIGITS}g}")


def counts(out: StudyOutcome) -> dict[str, int]:
    """How many designs (trials) the study has: total, done (ran to their end), failed,
    left (not run yet) and, with constraints, infeasible."""
    done = sum(r.ok for r in out.rows)
    failed = sum(not r.ok and r.status != "not run" for r in out.rows)
    return {
        "total": len(out.rows),
        "done": done,
        "failed": failed,
        "left": len(out.rows) - done - failed,
        "infeasible": sum(r.feasible is False for r in out.rows),
    }


def quantity(out: StudyOutcome, name: str) -> dict[str, Any]:
    """A parameter or metric as the page shows it: its unit as drawn and the factor from
    the study's own unit to it (Pa drawn in MPa: 1e-6), the study's unit, whether it is a
    number, on a log axis, and (text) its values."""
    factor, unit = P.scaled(out, name)
    entry: dict[str, Any] = {"name": name, "unit": unit, "factor": factor, "si_unit": out.unit(name) or "1"}
    if name in out.names:
        values = out.values(name)
        levels = P.distinct(values)
        entry.update(
            numeric=P.is_numeric(values),
            log=P.is_log(out, name, levels),
            levels=[_plain(v) for v in levels] if not P.is_numeric(values) else [],
        )
    else:
        entry.update(numeric=True, log=False, levels=[])
    return entry


def table_metrics(out: StudyOutcome, drawn: list[str]) -> list[str]:
    """The metrics of the page's table: the objectives, the constrained and targeted
    metrics and the main ones (`report.TABLE_METRICS`), those the study has, in the order
    drawn; the others are in each design's panel and the CSV table."""
    from granplate.study.report import TABLE_METRICS

    wanted = (
        set(out.objectives)
        | {b.metric for b in out.constraints}
        | set(TABLE_METRICS)
        | {m for t in out.report.targets for m in t.metrics}
    )
    return [m for m in drawn if m in wanted]


def _relative(folder: Path, path: Path) -> str:
    try:
        return Path(path).resolve().relative_to(folder.resolve()).as_posix()
    except ValueError:
        return Path(path).as_posix()


def design_entries(out: StudyOutcome, figures: dict[int, list[tuple[str, Path]]]) -> list[dict[str, Any]]:
    """One entry per row: number, key, status, ok, feasible, on the front, best for which
    metrics, why it was chosen, parameters and metrics (the study's own units, exact),
    its figures (caption, path relative to the page), its record and kept result file."""
    from granplate.study import report as R

    best = R.best_designs(out)
    front = set(R.pareto_front(out))
    chosen = R.chosen_designs(out, best)
    first = R.same_design(out)
    entries = []
    for i, r in enumerate(out.rows):
        record = D.record_path(out.folder, r.key) if r.key else None
        result = D.record_path(out.folder, r.key, ".nc") if r.key else None
        entries.append(
            {
                "i": i,
                "number": r.number,
                "key": r.key,
                "status": r.status,
                "ok": r.ok,
                "feasible": r.feasible,
                "front": i in front,
                "best": [m for m, j in best.items() if j == i],
                "why": chosen.get(i, ""),
                "same_as": first[i] if first[i] != i else None,
                "params": {n: _plain(r.params.get(n)) for n in out.names},
                "metrics": {m: _plain(r.metrics.get(m)) for m in out.metrics if r.metrics.get(m) is not None},
                "figures": [[caption, _relative(out.folder, p)] for caption, p in figures.get(i, [])],
                "record": _relative(out.folder, record) if record is not None and record.is_file() else None,
                "result": _relative(out.folder, result) if result is not None and result.is_file() else None,
            }
        )
    return entries


def explorer_data(out: StudyOutcome, figures: dict[int, list[tuple[str, Path]]] | None = None) -> dict[str, Any]:
    """The page's one blob of the study: title, kind, counts, the parameters and metrics
    (`quantity`), objectives, constraints, the table's metrics and every design
    (`design_entries`), figures: row -> [(caption, PNG)] of the chosen designs."""
    from granplate.study.report import directions, shown_metrics

    drawn, _ = shown_metrics(out)
    return {
        "title": out.folder.name,
        "kind": out.kind,
        "base": out.base,
        "version": gp.__version__,
        "counts": counts(out),
        "parameters": [quantity(out, n) for n in out.names],
        "metrics": [quantity(out, m) for m in out.metrics],
        "drawn": drawn,
        "table": table_metrics(out, drawn),
        "objectives": dict(out.objectives),
        "directions": directions(out),
        "constraints": [
            {"metric": b.metric, "low": b.low, "high": b.high, "text": b.text(out.unit(b.metric))}
            for b in out.constraints
        ],
        "gl": len(out.rows) > SCATTERGL_ABOVE,
        "designs": design_entries(out, figures or {}),
    }


# ------------------------------------------------------------------------- figures


def scatter_type(out: StudyOutcome) -> str:
    """'scattergl' above SCATTERGL_ABOVE designs, else 'scatter' (SVG)."""
    return "scattergl" if len(out.rows) > SCATTERGL_ABOVE else "scatter"


def axis_title(out: StudyOutcome, name: str, way: str = "") -> str:
    """'max_von_mises [MPa] (minimize)': a quantity, the unit of the values drawn (none for
    a parameter of text values, such as a material)."""
    text = name in out.names and not P.is_numeric(out.values(name))
    return name + ("" if text else f" [{P.scaled(out, name)[1]}]") + (f" ({way})" if way else "")


def _axis(out: StudyOutcome, name: str, way: str = "") -> dict[str, Any]:
    """A plotly axis of a quantity: its title with unit, log where the parameter is."""
    axis: dict[str, Any] = {
        "title": {"text": axis_title(out, name, way)},
        "automargin": True,
        "zeroline": False,
        "gridcolor": "#e5e5e5",
    }
    if name in out.names:
        values = out.values(name)
        if not P.is_numeric(values):
            axis["type"] = "category"
            axis["categoryorder"] = "array"
            axis["categoryarray"] = [str(v) for v in P.distinct(values)]
        elif P.is_log(out, name, P.distinct(values)):
            axis["type"] = "log"
    return axis


def _values(out: StudyOutcome, name: str, rows: list[int]) -> list[Any]:
    """The drawn values (unit drawn) of a parameter or metric over rows."""
    factor = P.scaled(out, name)[0]
    if name in out.names:
        return [
            _drawn(out.rows[i].params.get(name), factor)
            if not isinstance(out.rows[i].params.get(name), str)
            else out.rows[i].params.get(name)
            for i in rows
        ]
    return [_drawn(out.rows[i].metrics.get(name), factor) for i in rows]


def _points(
    kind: str, name: str, x: list, y: list, rows: list[int], colour: str, symbol: str = "circle", size: int = 7, **extra
) -> dict[str, Any]:
    return {
        "type": kind,
        "mode": "markers",
        "name": name,
        "x": x,
        "y": y,
        "customdata": rows,
        "marker": {"color": colour, "symbol": symbol, "size": size, "line": {"width": 0}},
        **extra,
    }


def pareto_figure(out: StudyOutcome) -> dict[str, Any] | None:
    """The designs in the plane of the first two objectives (one objective: against the
    design number): every feasible completed design (trace 'designs'), the infeasible ones
    as crosses, the Pareto front joined, the best design of each objective a star named in
    the legend (no label on the plot: none can overlap); None without objectives."""
    from granplate.study.report import best_designs, pareto_front

    names = list(out.objectives)
    if not names:
        return None
    kind = scatter_type(out)
    done = [i for i, r in enumerate(out.rows) if r.ok and r.metrics]
    two = len(names) >= 2

    def xy(rows: list[int]) -> tuple[list, list]:
        if two:
            return _values(out, names[0], rows), _values(out, names[1], rows)
        return [out.rows[i].number for i in rows], _values(out, names[0], rows)

    ok = [i for i in done if out.rows[i].feasible is not False]
    bad = [i for i in done if out.rows[i].feasible is False]
    traces = [
        _points(
            kind, "designs" + (" (feasible)" if out.constraints else ""), *xy(ok), ok, COLOURS["design"], meta="designs"
        )
    ]
    if bad:
        traces.append(
            _points(kind, "infeasible (constraints)", *xy(bad), bad, COLOURS["infeasible"], "x", meta="infeasible")
        )
    front = pareto_front(out)
    if front:
        order = sorted(front, key=lambda i: xy([i])[0][0])
        x, y = xy(order)
        traces.append(
            {
                **_points(kind, "Pareto front", x, y, order, COLOURS["front"], size=10),
                "mode": "lines+markers" if two else "markers",
                "line": {"color": COLOURS["front"]},
                "meta": "front",
            }
        )
    for k, (m, i) in enumerate(best_designs(out).items()):
        x, y = xy([i])
        colour, symbol = BEST_MARKERS[k % len(BEST_MARKERS)]
        traces.append(
            {
                **_points(
                    kind,
                    f"best {m}: {'trial' if out.kind == 'optimization' else 'design'} {out.rows[i].number}",
                    x,
                    y,
                    [i],
                    colour,
                    symbol,
                    15,
                ),
                "meta": "best",
            }
        )
    layout = {
        "xaxis": _axis(out, names[0], out.objectives[names[0]]) if two else {"title": {"text": "design"}},
        "yaxis": _axis(out, names[1] if two else names[0], out.objectives[names[1] if two else names[0]]),
        "legend": {"orientation": "h", "y": -0.18},
        "margin": {"t": 30, "r": 10},
        "dragmode": "select",
        "hovermode": "closest",
        "title": {"text": ""},
    }
    return {"data": traces, "layout": layout}


def main_metric(out: StudyOutcome) -> str | None:
    """The metric first drawn against the parameters: the first objective, else the first
    metric drawn."""
    from granplate.study.report import shown_metrics

    drawn, _ = shown_metrics(out)
    return next((m for m in list(out.objectives) + drawn if m in drawn), None)


def metric_figure(out: StudyOutcome, metric: str | None = None) -> dict[str, Any] | None:
    """A metric against each varied parameter, one panel each (log axes where the
    parameter is), infeasible designs as crosses; the page's selector swaps the metric.
    None when no metric varies."""
    metric = metric or main_metric(out)
    if metric is None:
        return None
    names = (P.varied(out) or list(out.names[:1]))[:MAX_PARAMETER_PANELS]
    kind = scatter_type(out)
    done = [i for i, r in enumerate(out.rows) if r.ok and r.metrics]
    ok = [i for i in done if out.rows[i].feasible is not False]
    bad = [i for i in done if out.rows[i].feasible is False]
    ncol = min(len(names), 4)
    nrow = math.ceil(len(names) / ncol)
    gap = 0.07
    layout: dict[str, Any] = {
        "showlegend": bool(bad),
        "hovermode": "closest",
        "dragmode": "select",
        "margin": {"t": 20, "r": 10},
        "height": 330 * nrow,
        "legend": {"orientation": "h", "y": 1.08},
    }
    traces = []
    for k, name in enumerate(names):
        row, col = divmod(k, ncol)
        suffix = "" if k == 0 else str(k + 1)
        x0 = col / ncol + (gap / 2 if col else 0)
        x1 = (col + 1) / ncol - (gap / 2 if col < ncol - 1 else 0)
        y1 = 1 - row / nrow
        y0 = 1 - (row + 1) / nrow + 0.16 / nrow
        layout[f"xaxis{suffix}"] = {**_axis(out, name), "domain": [x0, x1], "anchor": f"y{suffix}"}
        layout[f"yaxis{suffix}"] = {**_axis(out, metric), "domain": [y0, y1], "anchor": f"x{suffix}"}
        if col:
            layout[f"yaxis{suffix}"]["title"] = {"text": ""}
        for rows, label, colour, symbol in (
            (ok, "designs", COLOURS["design"], "circle"),
            (bad, "infeasible (constraints)", COLOURS["infeasible"], "x"),
        ):
            if rows:
                traces.append(
                    _points(
                        kind,
                        label,
                        _values(out, name, rows),
                        _values(out, metric, rows),
                        rows,
                        colour,
                        symbol,
                        7,
                        xaxis=f"x{suffix}",
                        yaxis=f"y{suffix}",
                        showlegend=k == 0,
                        meta={"parameter": name},
                    )
                )
    return {"data": traces, "layout": layout, "metric": metric, "parameters": names}


def _log_dimension(values: list[float]) -> dict[str, Any]:
    """A log-scaled parcoords axis: log10 of the values, ticks labelled with the values."""
    logs = [math.log10(v) for v in values]
    lo, hi = math.floor(min(logs)), math.ceil(max(logs))
    ticks = [t for t in np.arange(lo, hi + 1e-9, 1.0 if hi - lo > 1 else 0.25)]
    return {"values": logs, "tickvals": ticks, "ticktext": [f"{10**t:.3g}" for t in ticks]}


def parcoords_metrics(out: StudyOutcome) -> list[str]:
    """The metrics of the parallel coordinates: the objectives, constrained and targeted
    metrics, then the headline ones, those every completed design has."""
    from granplate.study.report import HEADLINE, shown_metrics

    drawn, _ = shown_metrics(out)
    done = [r for r in out.rows if r.ok and r.metrics]
    first = (
        list(out.objectives)
        + [b.metric for b in out.constraints]
        + [m for t in out.report.targets for m in t.metrics]
        + list(HEADLINE)
    )
    return [m for m in dict.fromkeys(first) if m in drawn and all(_plain(r.metrics.get(m)) is not None for r in done)]


def parcoords_figure(out: StudyOutcome) -> dict[str, Any] | None:
    """Parallel coordinates of the completed designs, the varied parameters (log axes
    where the parameter is; text values at their index) then the objectives and the other
    main metrics (`parcoords_metrics`), a constrained metric's axis naming its bound, lines
    coloured feasible / infeasible; `rows`: the design of each line. None without a
    completed design or a metric."""
    metrics = parcoords_metrics(out)
    rows = [i for i, r in enumerate(out.rows) if r.ok and r.metrics]
    if not rows or not metrics:
        return None
    dims = []
    for name in P.varied(out) or list(out.names):
        values = [out.rows[i].params.get(name) for i in rows]
        if not P.is_numeric(values):
            levels = [str(v) for v in P.distinct(out.values(name))]
            dim = {
                "values": [levels.index(str(v)) for v in values],
                "tickvals": list(range(len(levels))),
                "ticktext": levels,
            }
        else:
            shown_values = [_drawn(v, P.scaled(out, name)[0]) for v in values]
            dim = _log_dimension(shown_values) if P.is_log(out, name, P.distinct(values)) else {"values": shown_values}
        dims.append({**dim, "label": axis_title(out, name), "name": name})
    bounds = {b.metric: b for b in out.constraints}
    for m in metrics:
        factor, unit = P.scaled(out, m)
        label = axis_title(out, m, out.objectives.get(m, ""))
        if m in bounds:
            b = bounds[m]
            label += " in " + (
                f"{level_label(b.low * factor) if b.low is not None else '-inf'} .. "
                f"{level_label(b.high * factor) if b.high is not None else 'inf'}"
            )
        dims.append({"values": _values(out, m, rows), "label": label, "name": m})
    feasible = [0 if out.rows[i].feasible is False else 1 for i in rows]
    line = {
        "color": feasible,
        "cmin": 0,
        "cmax": 1,
        "showscale": False,  # 0.5: filtered out elsewhere
        "colorscale": [
            [0, COLOURS["infeasible"]],
            [0.45, COLOURS["infeasible"]],
            [0.5, "#ececec"],
            [0.55, COLOURS["design"]],
            [1, COLOURS["design"]],
        ],
    }
    return {
        "data": [{"type": "parcoords", "dimensions": dims, "line": line, "labelangle": -12, "labelside": "top"}],
        "layout": {"margin": {"t": 90, "l": 70, "r": 70, "b": 30}, "height": 460},
        "rows": rows,
    }


def level_label(v: Any) -> str:
    """A parameter's value as a category label: whole numbers in full (50000, not 5e+04),
    others to 4 significant digits, text as it is."""
    if isinstance(v, float) and v.is_integer() and abs(v) < 1e7:
        return str(int(v))
    return f"{v:.4g}" if isinstance(v, float) else str(v)


def heat_metrics(out: StudyOutcome) -> list[str]:
    """The metrics of the heat maps: the objectives, the headline metrics and the
    targets' metrics, those drawn."""
    from granplate.study.report import HEADLINE, shown_metrics

    drawn, _ = shown_metrics(out)
    targets = [m for t in out.report.targets for m in t.metrics]
    return [m for m in dict.fromkeys(list(out.objectives) + list(HEADLINE) + targets) if m in drawn]


def heat_figure(out: StudyOutcome) -> dict[str, Any] | None:
    """The heat maps of a grid study: one trace per metric (`heat_metrics`) and per value
    of the other parameters (at most `plots.MAX_PANELS`, the slowest sliced at their first
    value), cells labelled with their value, the cell's design as customdata (-1: none);
    the page's selectors show one trace. None unless the study is a grid of two."""
    axes_ = P.heat_axes(out)
    metrics = heat_metrics(out)
    if axes_ is None or not metrics:
        return None
    xn, yn, others = axes_
    xl, yl = P.distinct(out.values(xn)), P.distinct(out.values(yn))
    combos = list(itertools.product(*(P.distinct(out.values(n)) for n in others)))
    keep = list(others)
    while keep and math.prod(len(P.distinct(out.values(n))) for n in keep) > P.MAX_PANELS:
        keep.pop(0)
    fixed = {n: P.distinct(out.values(n))[0] for n in others if n not in keep}
    combos = [c for c in combos if all(str(c[others.index(n)]) == str(v) for n, v in fixed.items())]

    def tick(name: str, levels: list) -> list[str]:
        return [level_label(v) for v in P.scaled_values(out, name, levels)]

    traces, index = [], []
    for m in metrics:
        factor, unit = P.scaled(out, m)
        for combo in combos:
            z = [[None] * len(xl) for _ in yl]
            cell = [[-1] * len(xl) for _ in yl]
            for i, r in enumerate(out.rows):
                if all(str(r.params.get(n)) == str(v) for n, v in zip(others, combo)):
                    a = [str(v) for v in yl].index(str(r.params.get(yn)))
                    b = [str(v) for v in xl].index(str(r.params.get(xn)))
                    z[a][b] = _drawn(r.metrics.get(m), factor) if r.ok else None
                    cell[a][b] = i
            where = ", ".join(
                f"{n} = {P._with_unit(out, n, v)}" for n, v in list(zip(others, combo)) + list(fixed.items())
            )
            index.append({"metric": m, "slice": where})
            traces.append(
                {
                    "type": "heatmap",
                    "x": tick(xn, xl),
                    "y": tick(yn, yl),
                    "z": z,
                    "customdata": cell,
                    "text": [[P._cell_text(v) if v is not None else "" for v in row] for row in z],
                    "texttemplate": "%{text}",
                    "colorscale": "Viridis",
                    "visible": not traces,
                    "colorbar": {"title": {"text": f"{m} [{unit}]", "side": "right"}},
                    "name": f"{m} {where}".strip(),
                    "hoverongaps": False,
                    "xgap": 1,
                    "ygap": 1,
                }
            )
    layout = {
        "xaxis": {**_axis(out, xn), "type": "category"},
        "yaxis": {**_axis(out, yn), "type": "category"},
        "margin": {"t": 20, "r": 10},
    }
    return {"data": traces, "layout": layout, "index": index, "x": xn, "y": yn, "others": others}


def explorer_figures(out: StudyOutcome) -> dict[str, Any]:
    """The page's figures as plotly JSON: pareto, parcoords, metric, heat (None: the
    study has no such view), and which of them is the first screen's ('main')."""
    figs = {
        "pareto": pareto_figure(out),
        "parcoords": parcoords_figure(out),
        "metric": metric_figure(out),
        "heat": heat_figure(out),
    }
    figs["main"] = "pareto" if figs["pareto"] else "heat" if figs["heat"] else "metric" if figs["metric"] else None
    return figs


# ------------------------------------------------------------------------- the page


def plotly_source() -> Path:
    """plotly.min.js as the plotly package ships it."""
    import plotly

    return Path(plotly.__file__).parent / "package_data" / PLOTLY_JS


def plotly_version() -> str:
    """The version of plotly.js shipped beside the page ('plotly.js vX.Y.Z' header)."""
    head = plotly_source().read_bytes()[:200].decode("ascii", "replace")
    return next((w[1:] for w in head.split() if w.startswith("v") and w[1:2].isdigit()), "?")


def _copy(source: Path, target: Path) -> None:
    if not (
        target.is_file()
        and target.stat().st_size == source.stat().st_size
        and target.read_bytes() == source.read_bytes()
    ):
        shutil.copyfile(source, target)


def copy_assets(folder: Path) -> Path:
    """DIR/report_assets/: plotly.min.js (with a note of its version and licence) and the
    page's script and style, copied where missing or different; the folder."""
    assets = Path(folder) / ASSETS
    assets.mkdir(parents=True, exist_ok=True)
    _copy(plotly_source(), assets / PLOTLY_JS)
    note = (
        f"{PLOTLY_JS}: plotly.js v{plotly_version()}, copied from the plotly Python package.\n"
        "Copyright Plotly, Inc. Licensed under the MIT license (https://github.com/plotly/plotly.js).\n"
        "explorer.js, explorer.css: granplate's study page, MIT license.\n"
    )
    if not (assets / PLOTLY_NOTE).is_file() or (assets / PLOTLY_NOTE).read_text() != note:
        (assets / PLOTLY_NOTE).write_text(note)
    for name in OWN_ASSETS:
        with resources.as_file(resources.files("granplate.study") / "assets" / name) as source:
            _copy(source, assets / name)
    return assets


def _inline(text: str) -> str:
    """Escaped text; **bold** and `code` as tags."""
    import re

    s = html.escape(text)
    s = re.sub(r"\*\*(.+?)\*\*", r"<strong>\1</strong>", s)
    return re.sub(r"`(.+?)`", r"<code>\1</code>", s)


def _table(header: tuple[str, ...], rows: tuple[tuple[str, ...], ...], cls: str = "") -> str:
    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    verdicts = {"yes": "yes", "pass": "yes", "no": "no", "FAIL": "no"}
    body = "".join(
        "<tr>"
        + "".join((f"<td class='{verdicts[c]}'>" if c in verdicts else "<td>") + f"{_inline(c)}</td>" for c in r)
        + "</tr>"
        for r in rows
    )
    return (
        f"<div class='table-wrap'><table class='{cls}'><thead><tr>{head}</tr></thead>"
        f"<tbody>{body}</tbody></table></div>"
    )


def _blocks_html(blocks) -> str:
    """The report's blocks of a section (headings, paragraphs, lists, tables) as HTML."""
    out = []
    for b in blocks:
        if b.kind in ("h2", "h3"):
            out.append(f"<{b.kind}>{_inline(b.text)}</{b.kind}>")
        elif b.kind == "p" and b.text:
            lines = b.text.split("\n")
            if all(ln.startswith("- ") for ln in lines):
                out.append("<ul>" + "".join(f"<li>{_inline(ln[2:])}</li>" for ln in lines) + "</ul>")
            else:
                out.append(f"<p>{_inline(b.text)}</p>")
        elif b.kind == "table":
            out.append(_table(b.header, b.rows, "sortable"))
        elif b.kind == "code":
            out.append(f"<pre>{html.escape(b.text)}</pre>")
    return "\n".join(out)


def _json(value: Any) -> str:
    """JSON safe inside a <script> element."""
    return json.dumps(value, separators=(",", ":"), allow_nan=False).replace("</", "<\\/")


def counts_text(c: dict[str, int], kind: str) -> str:
    """'80 trials: 80 done, 0 failed, 0 left (12 infeasible)'."""
    what = "trials" if kind == "optimization" else "designs"
    return f"{c['total']} {what}: {c['done']} done, {c['failed']} failed, {c['left']} left" + (
        f" ({c['infeasible']} infeasible)" if c["infeasible"] else ""
    )


def explorer_html(
    out: StudyOutcome, data: dict[str, Any], figures: dict[str, Any], paper_figures: list[Path], live: bool = False
) -> str:
    """The page: the answer first (counts, conclusion, best designs, the main figure, the
    targets' verdicts), then the views to explore, the table, failures, the study file
    (collapsed) and the figures for papers; `live`: it reloads itself every REFRESH_S seconds while
    designs are left."""
    c = data["counts"]
    what = "optimisation" if out.kind == "optimization" else "sweep"
    title = f"Study {out.folder.name}: {what} of {out.base or 'a scenario'}"
    refresh = f"<meta http-equiv='refresh' content='{REFRESH_S}'>" if live and c["left"] else ""
    parts = [
        *_page_header(out, c, title, refresh),
        *_answer_sections(out, figures),
        *_explore_section(figures),
        *_closing_sections(out, data, figures, paper_figures),
    ]
    return "\n".join(p for p in parts if p) + "\n"


def _page_header(out: StudyOutcome, c: dict, title: str, refresh: str) -> list[str]:
    """The page's head and header: the title, the counts (and whether it reloads), how
    to read and explore it."""
    running = " <span class='live'>(running: this page reloads as designs arrive)</span>" if refresh else ""
    return [
        "<!DOCTYPE html>",
        "<html lang='en'><head><meta charset='utf-8'>",
        refresh,
        "<meta name='viewport' content='width=device-width, initial-scale=1'>",
        f"<title>{html.escape(title)}</title>",
        f"<link rel='stylesheet' href='{ASSETS}/explorer.css'>",
        f"<script src='{ASSETS}/{PLOTLY_JS}'></script>",
        "</head><body>",
        "<header>",
        f"<h1>{html.escape(title)}</h1>",
        f"<p class='counts'><span id='counts'>{html.escape(counts_text(c, out.kind))}</span>{running}. "
        f"Made by granplate {html.escape(gp.__version__)}; the whole table is "
        f"<code>{'trials.csv' if out.kind == 'optimization' else 'results.csv'}</code>; "
        "Pa are shown in MPa, dimensionless quantities as [-]. Hover a point for its design, "
        "click it for its panel, drag a box (or a range on an axis of the parallel coordinates) to filter.</p>",
        "</header>",
    ]


def _answer_sections(out: StudyOutcome, figures: dict[str, Any]) -> list[str]:
    """The answer first: the conclusion, the best designs, the main figure, then the
    targets' verdicts."""
    from granplate.study import report as R

    conclusion = "".join(f"<p>{_inline(p.strip())}</p>" for p in out.report.conclusion.split("\n\n") if p.strip())
    main = figures.get("main")
    main_title = {
        "pareto": "Pareto front of the objectives",
        "heat": "Heat map",
        "metric": "Metrics against the parameters",
    }.get(main or "", "")
    targets = R._targets(out)
    targets = [
        b
        for b in targets
        if b.kind != "h2"
        and not (b.kind == "h3" and b.text == "Conclusion")
        and not (b.kind == "p" and out.report.conclusion and b.text.strip() in out.report.conclusion)
    ]
    return [
        "<section id='answer'>",
        "<div class='answer-text'>",
        (f"<div id='conclusion' class='conclusion'><h2>Conclusion</h2>{conclusion}</div>" if conclusion else ""),
        "<h2>Best designs</h2><div id='best'></div>",
        "</div>",
        f"<div class='answer-plot'><h2>{main_title}</h2>",
        (
            "<div class='heat-choice'><label>metric <select id='heat-metric'></select></label> "
            "<label id='heat-slice-label'>slice <select id='heat-slice'></select></label></div>"
            if main == "heat"
            else ""
        ),
        "<div id='fig-main' class='plot main-plot'></div></div>",
        "</section>",
        (f"<section id='targets'><h2>Targets</h2>{_blocks_html(targets)}</section>" if targets else ""),
    ]


def _explore_section(figures: dict[str, Any]) -> list[str]:
    """The views to explore: filters, parallel coordinates, metrics, heat maps, the table."""
    main = figures.get("main")
    return [
        "<section id='explore'><h2>Explore</h2>",
        "<div class='filterbar'><span id='shown'></span> <label><input type='checkbox' id='only-feasible'> "
        "feasible only</label> <label><input type='checkbox' id='only-front'> on the front only</label> "
        "<button id='reset' type='button'>show all</button></div>",
        (
            "<h3>Parallel coordinates: parameters to objectives</h3><div id='fig-parcoords' class='plot'></div>"
            if figures.get("parcoords")
            else ""
        ),
        (
            "<h3>Metrics against the parameters</h3><label>metric <select id='metric-choice'></select></label>"
            "<div id='fig-metric' class='plot'></div>"
            if figures.get("metric")
            else ""
        ),
        (
            "<h3>Heat maps</h3><label>metric <select id='heat-metric'></select></label> "
            "<label id='heat-slice-label'>slice <select id='heat-slice'></select></label>"
            "<div id='fig-heat' class='plot'></div>"
            if figures.get("heat") and main != "heat"
            else ""
        ),
        "<h3>Designs</h3><p class='hint'>Click a column to sort, a row for the design's panel.</p>",
        "<div class='table-wrap' id='table-wrap'><table id='designs'></table></div>",
        "</section>",
    ]


def _closing_sections(out: StudyOutcome, data: dict[str, Any], figures: dict[str, Any], paper_figures) -> list[str]:
    """Failures, the study file (collapsed), the figures for papers, the design panel and
    the page's data and scripts."""
    from granplate.study import report as R

    failures = R._failures(out)
    definition = R._definition(out)
    paper = "".join(
        f"<li><a href='{html.escape(_relative(out.folder, p))}'>{html.escape(p.name)}</a></li>" for p in paper_figures
    )
    return [
        f"<section id='failures'>{_blocks_html(failures)}</section>",
        f"<details id='study'><summary>The study: its definition and the study file as run</summary>"
        f"{_blocks_html(definition)}</details>",
        (
            f"<details id='paper-figures'><summary>Figures for papers (PNG, PDF)</summary><ul>{paper}</ul>"
            "<p>and the same page as Markdown: <a href='report.md'>report.md</a>.</p></details>"
            if paper
            else ""
        ),
        "<aside id='panel' class='panel' hidden></aside>",
        f"<script id='study-data' type='application/json'>{_json(data)}</script>",
        f"<script id='study-figures' type='application/json'>{_json(figures)}</script>",
        f"<script src='{ASSETS}/explorer.js'></script>",
        "</body></html>",
    ]


def write_explorer(
    out: StudyOutcome,
    design_figures: dict[int, list[tuple[str, Path]]] | None = None,
    paper_figures: list[Path] | None = None,
    live: bool = False,
    page: Path | None = None,
) -> Path:
    """Write the page (DIR/report.html unless `page`) and its assets folder beside it; the
    page (rewritten only when its text changes)."""
    from granplate.store import atomic_write

    page = Path(page) if page is not None else out.folder / "report.html"
    copy_assets(page.parent)
    text = explorer_html(out, explorer_data(out, design_figures), explorer_figures(out), paper_figures or [], live)
    if not (page.is_file() and page.read_text() == text):
        atomic_write(page, lambda tmp: tmp.write_text(text))
    return page

"""Figures of a study (its report page): each metric against each parameter, heat maps of
a metric over two grid parameters (one panel per value of the others), and the Pareto
front of an optimisation. Every axis and colour bar names its quantity and unit, and the
values drawn on it are in that unit (`scaled`: Pa shown in MPa, parameters as metrics); a
parameter spaced with `log = true` is drawn on a log axis.

Figures are `matplotlib.figure.Figure` objects on the Agg canvas (granplate.figures.common);
the drawn quantities carry a `gid` naming them, for the tests.
"""

from __future__ import annotations

import itertools
import math
from typing import Any

from typing import TYPE_CHECKING

import numpy as np

from granplate.figures.common import new_figure
from granplate.study.outcome import StudyOutcome

if TYPE_CHECKING:  # matplotlib loads when a figure is drawn
    from matplotlib.figure import Figure

#: Units shown scaled: unit -> (factor, shown unit).
SHOWN_UNITS: dict[str, tuple[float, str]] = {"Pa": (1e-6, "MPa")}
#: Most lines drawn with a legend in a metric-versus-parameter panel (more: no legend).
MAX_LEGEND = 8
#: Most panels of a heat-map figure; beyond, the other parameters are sliced at their
#: first value (said in the title).
MAX_PANELS = 9
#: Size of one panel [inches] and the PNG resolution [dots per inch] of a study figure.
PANEL = (3.4, 2.8)
DPI = 100
#: Font size [pt] of a heat map's cell values and tick labels (8 pt: 11 px at DPI).
HEAT_FONT = 8
#: Room [inches] a heat-map cell takes at least (width for "1.23e+04" at HEAT_FONT,
#: height for one line), and the margin of a panel around its cells (labels, ticks).
HEAT_CELL = (0.62, 0.34)
HEAT_MARGIN = (1.5, 1.2)


def shown(unit: str) -> tuple[float, str]:
    """(factor, unit) to draw a quantity of `unit` in ("Pa" -> MPa; "1" -> "-")."""
    if unit in SHOWN_UNITS:
        return SHOWN_UNITS[unit]
    return 1.0, ("-" if unit in ("1", "") else unit)


def scaled(out: StudyOutcome, name: str) -> tuple[float, str]:
    """(factor, unit) a metric's or parameter's values are drawn in: the one source of the
    number on an axis and the unit in its label."""
    return shown(out.unit(name))


def scaled_values(out: StudyOutcome, name: str, values: list[Any]) -> list[Any]:
    """Values of `name` in the unit drawn (`scaled`); text and missing values as they are."""
    factor = scaled(out, name)[0]
    return [v * factor if isinstance(v, (int, float)) and not isinstance(v, bool) else v for v in values]


def is_log(out: StudyOutcome, name: str, levels: list[Any]) -> bool:
    """Whether parameter `name` is drawn on a log axis: the study spaces it with `log =
    true`, or its positive values span a factor of 50 or more (three or more of them)."""
    if not is_numeric(levels) or not levels or min(levels) <= 0:
        return False
    return name in out.log_parameters or (len(levels) > 2 and max(levels) / min(levels) >= 50)


def label(out: StudyOutcome, name: str) -> str:
    """'max_von_mises [MPa]', 'ep_max_fraction [-]': the axis label of a quantity (a
    parameter's companions, those that vary with it, are named after it)."""
    text = f"{name} [{scaled(out, name)[1]}]"
    if name in out.names:
        text += "".join(f"\nwith {n} [{scaled(out, n)[1]}]" for n in companions(out, name))
    return text


def is_numeric(values: list[Any]) -> bool:
    return all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values if v is not None)


def distinct(values: list[Any]) -> list[Any]:
    """The distinct values in order of appearance (numbers sorted)."""
    seen = list(dict.fromkeys(v for v in values if v is not None))
    return sorted(seen) if is_numeric(seen) else seen


def is_grid(out: StudyOutcome, names: tuple[str, ...] | None = None) -> bool:
    """Whether the rows are the full grid of the distinct values of `names` (default: the
    varied parameters, one of each group that varies together), each combination once."""
    names = tuple(varied(out)) if names is None else names
    combos = {tuple(str(r.params.get(n)) for n in names) for r in out.rows}
    size = math.prod(len(distinct(out.values(n))) for n in names)
    return len(combos) == len(out.rows) == size


def tied(out: StudyOutcome, a: str, b: str) -> bool:
    """Whether parameters a and b vary together, one value of b for each value of a and
    the reverse (a [zip] table); never in a sample where each design has values of its own."""
    pairs = {(str(x), str(y)) for x, y in zip(out.values(a), out.values(b))}
    if len(pairs) == len({str(r.params) for r in out.rows}) > 2:
        return False  # every design has its own values (a sample): nothing ties them
    return len(pairs) == len({p[0] for p in pairs}) == len({p[1] for p in pairs})


def varied(out: StudyOutcome) -> list[str]:
    """The parameters that take more than one value, one of each group that varies
    together (the first: the others follow it, `companions`)."""
    names: list[str] = []
    for n in out.names:
        if len(distinct(out.values(n))) > 1 and not any(tied(out, m, n) for m in names):
            names.append(n)
    return names


def companions(out: StudyOutcome, name: str) -> list[str]:
    """The parameters that vary together with `name` (after it in the study)."""
    later = out.names[out.names.index(name) + 1 :]
    return [n for n in later if len(distinct(out.values(n))) > 1 and tied(out, name, n)]


def _positions(values: list[Any], levels: list[Any]) -> np.ndarray:
    """x of each value: the value itself (numbers) or its index among the levels."""
    if is_numeric(levels):
        return np.array([np.nan if v is None else float(v) for v in values])
    index = {str(v): k for k, v in enumerate(levels)}
    return np.array([index.get(str(v), np.nan) for v in values], dtype=float)


def _x_axis(ax, out: StudyOutcome, name: str, levels: list[Any]) -> None:
    ax.set_xlabel(label(out, name), fontsize=8)
    if not is_numeric(levels):
        ax.set_xticks(range(len(levels)), [str(v) for v in levels], fontsize=8)
        ax.set_xlim(-0.5, len(levels) - 0.5)
    elif is_log(out, name, levels):
        ax.set_xscale("log")


def _short(v: Any) -> str:
    return f"{v:.4g}" if isinstance(v, float) else str(v)


def _with_unit(out: StudyOutcome, name: str, v: Any) -> str:
    """A parameter's value in the unit drawn, with the unit unless dimensionless or text."""
    shown_v = scaled_values(out, name, [v])[0]
    unit = scaled(out, name)[1]
    numeric = isinstance(v, (int, float)) and not isinstance(v, bool)
    return _short(shown_v) + (f" {unit}" if numeric and unit not in ("-", "") else "")


def fig_metric(out: StudyOutcome, metric: str) -> Figure:
    """The metric against each varied parameter, one panel each. On a grid, the designs
    that share the other parameters are joined by a line, coloured by the value of the
    other parameter with the fewest values (text before numbers; the legend); otherwise each design is a
    point. Infeasible designs are crosses."""
    names = varied(out) or list(out.names[:1])
    factor, _ = scaled(out, metric)
    y = np.array(out.metric(metric)) * factor
    grid = is_grid(out)
    fig = new_figure(PANEL[0] * max(1, len(names)), PANEL[1] + 0.4)
    axes = fig.subplots(1, max(1, len(names)), squeeze=False)[0]
    infeasible = np.array([r.feasible is False for r in out.rows])
    for ax, name in zip(axes, names):
        levels = distinct(scaled_values(out, name, out.values(name)))
        x = _positions(scaled_values(out, name, out.values(name)), levels)
        others = [n for n in names if n != name]
        if grid and others:
            # one line per combination of the others, coloured by the one with fewest values
            # (a named choice, such as a material, before a number)
            hue = min(others, key=lambda n: (len(distinct(out.values(n))), is_numeric(out.values(n)), others.index(n)))
            colours = {str(v): f"C{k % 10}" for k, v in enumerate(distinct(out.values(hue)))}
            groups: dict[tuple, list[int]] = {}
            for i, r in enumerate(out.rows):
                groups.setdefault(tuple(r.params.get(n) for n in others), []).append(i)
            named: set[str] = set()
            for g, idx in groups.items():
                idx = sorted(idx, key=lambda i: x[i])
                value = str(g[others.index(hue)])
                text = (
                    f"{hue.rsplit('.', 1)[-1]} = {_with_unit(out, hue, g[others.index(hue)])}"
                    if value not in named
                    else None
                )
                named.add(value)
                ax.plot(
                    x[idx],
                    y[idx],
                    "o-",
                    ms=3,
                    lw=1,
                    color=colours[value],
                    alpha=0.8,
                    label=text,
                    gid=f"{metric}-vs-{name}",
                )
            if len(colours) <= MAX_LEGEND:
                ax.legend(fontsize=6, loc="best")
        else:
            ok = ~infeasible
            ax.plot(x[ok], y[ok], "o", ms=4, color="C0", gid=f"{metric}-vs-{name}")
        if infeasible.any():
            ax.plot(
                x[infeasible],
                y[infeasible],
                "x",
                ms=5,
                color="0.4",
                label="infeasible",
                gid=f"{metric}-vs-{name}-infeasible",
            )
        _x_axis(ax, out, name, levels)
        ax.set_ylabel(label(out, metric), fontsize=8)
        ax.tick_params(labelsize=7)
        ax.grid(True, lw=0.3, alpha=0.5)
    fig.suptitle(
        f"{metric} against the parameters ({sum(np.isfinite(y))} of {len(y)} designs with a value)", fontsize=9
    )
    return fig


def heat_axes(out: StudyOutcome) -> tuple[str, str, list[str]] | None:
    """(x, y, the others) of a study's heat maps: the two varied parameters with the most
    values (numbers first) when the study is a grid of two or more; else None."""
    names = varied(out)
    if len(names) < 2 or not is_grid(out, tuple(names)):
        return None
    ranked = sorted(names, key=lambda n: (-len(distinct(out.values(n))), not is_numeric(out.values(n)), names.index(n)))
    x, y = ranked[0], ranked[1]
    return x, y, [n for n in names if n not in (x, y)]


def heat_panel_size(nx: int, ny: int) -> tuple[float, float]:
    """(width, height) [inches] of a heat-map panel of nx x ny cells: at least PANEL, and
    enough for each cell's value at HEAT_FONT (HEAT_CELL) plus the labels (HEAT_MARGIN)."""
    return (max(PANEL[0], HEAT_MARGIN[0] + HEAT_CELL[0] * nx), max(PANEL[1], HEAT_MARGIN[1] + HEAT_CELL[1] * ny))


def _tick(v: Any) -> str:
    return f"{v:.3g}" if isinstance(v, float) else str(v)


def _cell_text(v: float) -> str:
    return "" if not np.isfinite(v) else f"{v:.3g}"


def fig_heatmap(out: StudyOutcome, metric: str) -> Figure | None:
    """The metric over the heat-map parameters (`heat_axes`), one panel per combination
    of the other parameters (sliced at their first value beyond MAX_PANELS panels), the
    value written in each cell; None when the study is not a grid of two parameters."""
    axes_ = heat_axes(out)
    if axes_ is None:
        return None
    xn, yn, others = axes_
    xl, yl = distinct(out.values(xn)), distinct(out.values(yn))
    combos = list(itertools.product(*(distinct(out.values(n)) for n in others)))
    sliced = ""
    if len(combos) > MAX_PANELS:  # slice the slowest other parameters at their first value
        keep = list(others)
        while keep and math.prod(len(distinct(out.values(n))) for n in keep) > MAX_PANELS:
            keep.pop(0)
        fixed = {n: distinct(out.values(n))[0] for n in others if n not in keep}
        sliced = "; " + ", ".join(f"{n} = {_with_unit(out, n, v)}" for n, v in fixed.items())
        combos = [c for c in combos if all(str(c[others.index(n)]) == str(v) for n, v in fixed.items())]
    factor, unit = scaled(out, metric)
    values = np.array(out.metric(metric)) * factor
    finite = values[np.isfinite(values)]
    lo, hi = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
    ncol = len(combos) if len(combos) <= 3 else math.ceil(math.sqrt(len(combos)))
    nrow = math.ceil(len(combos) / ncol)
    width, height = heat_panel_size(len(xl), len(yl))
    fig = new_figure(width * ncol + 1.2, height * nrow + 0.6)
    grid = fig.subplots(nrow, ncol, squeeze=False)
    image = None
    for k, combo in enumerate(combos):
        ax = grid[k // ncol][k % ncol]
        z = np.full((len(yl), len(xl)), np.nan)
        for i, r in enumerate(out.rows):
            if all(str(r.params.get(n)) == str(v) for n, v in zip(others, combo)):
                z[
                    [str(v) for v in yl].index(str(r.params.get(yn))), [str(v) for v in xl].index(str(r.params.get(xn)))
                ] = values[i]
        image = ax.imshow(z, origin="lower", aspect="auto", cmap="viridis", vmin=lo, vmax=hi, gid=f"heatmap-{metric}")
        for (a, b), v in np.ndenumerate(z):
            ax.text(
                b,
                a,
                _cell_text(v),
                ha="center",
                va="center",
                fontsize=HEAT_FONT,
                color="w" if np.isfinite(v) and v < (lo + hi) / 2 else "k",
                gid=f"cell-{metric}",
            )
        ax.set_xticks(
            range(len(xl)),
            [_tick(v) for v in scaled_values(out, xn, xl)],
            fontsize=HEAT_FONT,
            rotation=30 if len(xl) > 6 else 0,
        )
        ax.set_yticks(range(len(yl)), [_tick(v) for v in scaled_values(out, yn, yl)], fontsize=HEAT_FONT)
        ax.set_xlabel(label(out, xn), fontsize=HEAT_FONT)
        ax.set_ylabel(label(out, yn), fontsize=HEAT_FONT)
        if others:
            ax.set_title("\n".join(f"{n} = {_with_unit(out, n, v)}" for n, v in zip(others, combo)), fontsize=HEAT_FONT)
    for k in range(len(combos), nrow * ncol):
        grid[k // ncol][k % ncol].set_visible(False)
    if image is not None:
        bar = fig.colorbar(image, ax=grid.ravel().tolist(), shrink=0.9)
        bar.set_label(f"{metric} [{unit}]", fontsize=HEAT_FONT)
        bar.ax.tick_params(labelsize=HEAT_FONT)
    fig.suptitle(f"{metric} [{unit}]{sliced}", fontsize=9)
    return fig


def fig_pareto(out: StudyOutcome, front: list[int], chosen: dict[str, int]) -> Figure | None:
    """Every completed trial in the plane of the first two objectives (one objective:
    against the trial number), the feasible Pareto front joined, infeasible trials as
    crosses, the chosen designs named; None without objectives."""
    names = list(out.objectives)
    if not names:
        return None
    done = [i for i, r in enumerate(out.rows) if r.ok and r.metrics]
    two = len(names) >= 2
    fx = scaled(out, names[0])[0]
    fy = scaled(out, names[1])[0] if two else 1.0

    def xy(i: int) -> tuple[float, float]:
        m = out.rows[i].metrics
        if two:
            return float(m.get(names[0]) or np.nan) * fx, float(m.get(names[1]) or np.nan) * fy
        return float(out.rows[i].number), float(m.get(names[0]) or np.nan) * fx

    fig = new_figure(5.6, 4.2)
    ax = fig.subplots()
    ok = [i for i in done if out.rows[i].feasible is not False]
    bad = [i for i in done if out.rows[i].feasible is False]
    ax.scatter(*zip(*[xy(i) for i in ok]) if ok else ([], []), s=14, color="0.6", label="trials", gid="trials")
    if bad:
        ax.scatter(
            *zip(*[xy(i) for i in bad]),
            s=22,
            marker="x",
            color="0.35",
            label="infeasible (constraints)",
            gid="infeasible",
        )
    if front:
        pts = sorted(xy(i) for i in front)
        ax.plot(*zip(*pts), "o-" if two else "o", color="C3", ms=5, label="Pareto front", gid="front")
    by_row: dict[int, list[str]] = {}
    for metric, i in chosen.items():
        by_row.setdefault(i, []).append(metric)
    for i, metrics in by_row.items():
        ax.annotate(f"best {', '.join(metrics)}", xy(i), fontsize=7, xytext=(6, 6), textcoords="offset points")
    if two:
        ax.set_xlabel(f"{label(out, names[0])} ({out.objectives[names[0]]})", fontsize=8)
        ax.set_ylabel(f"{label(out, names[1])} ({out.objectives[names[1]]})", fontsize=8)
    else:
        ax.set_xlabel("trial", fontsize=8)
        ax.set_ylabel(f"{label(out, names[0])} ({out.objectives[names[0]]})", fontsize=8)
    ax.grid(True, lw=0.3, alpha=0.5)
    ax.legend(fontsize=7)
    ax.set_title(f"{out.base}: {len(done)} completed trials", fontsize=9)
    return fig

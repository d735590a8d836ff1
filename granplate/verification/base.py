"""The pieces every verification case is made of: checks, case results, the registry.

A *check* compares one number the simulator produced ("ours") with an independent
reference (a closed form, a published value, an independent high-accuracy solution),
under a tolerance that is justified in words on the page. A *case* runs one physical
situation (usually a scenario file under `verification/scenarios/`): its `run` computes
and returns the checks (and the numbers its figure shows, `CaseResult.plot`), its `draw`
turns those numbers into one figure. The checks thus run without matplotlib
(`Context(figures=False)`).

Check kinds (how `error` and `passed` are computed):

- "rel": error = |ours - reference| / |reference|, passes when error <= tolerance;
- "abs": error = |ours - reference|, passes when error <= tolerance;
- "max": an upper bound: error = ours, passes when ours <= tolerance (reference is the
  ideal value, usually 0);
- "min": a lower bound: error = ours, passes when ours >= tolerance.
"""

from __future__ import annotations

import math
import time
import traceback
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from granplate.results import criteria

#: Folder (inside the output directory) that holds the figures.
FIGURE_DIR = "validation-figures"

#: Machine epsilon of float64.
EPS = float(np.finfo(float).eps)


def Check(
    quantity: str,
    unit: str,
    reference: float,
    source: str,
    ours: float,
    tolerance: float,  # noqa: N802
    why: str,
    kind: str = "rel",
) -> criteria.Check:
    """One number against its reference: a granplate.results.criteria.Check whose
    criterion is given by `kind` and `tolerance` (see the module docstring).

    quantity: what is compared (with the setting, e.g. "t_c, glass"); unit: its unit
    ("-" for none); reference: the true value; source: where the reference comes from;
    ours: the simulator's value; why: one sentence justifying the tolerance (time-step
    order, mesh order, offsets). ValueError for an unknown kind.
    """
    return criteria.Check(quantity, unit, reference, source, ours, criteria.criterion_of_kind(kind, tolerance), why)


@dataclass
class CaseResult:
    """What one case returns: its checks, its figure, a description and notes.

    description: what is run and against which truth (Markdown, a paragraph);
    figure: file name inside FIGURE_DIR (None when the case crashed before plotting);
    notes: extra sentences for the page (known limitations, what is out of scope);
    tables: extra Markdown tables (the convergence studies); crashed: the traceback
    when the case raised (the case then fails); plot: the numbers the case's `draw` makes
    its figure from (not written to the page). A case returns `CaseResult.of(...)`; the
    registry fills in name, family, title, figure and seconds (`run_case`).
    """

    name: str
    family: str
    title: str
    description: str = ""
    checks: list[criteria.Check] = field(default_factory=list)
    figure: str | None = None
    notes: list[str] = field(default_factory=list)
    tables: list[str] = field(default_factory=list)
    seconds: float = 0.0
    crashed: str | None = None
    plot: dict[str, Any] = field(default_factory=dict, repr=False)

    @classmethod
    def of(
        cls,
        description: str,
        checks: Sequence[criteria.Check],
        *,
        notes: Sequence[str] = (),
        tables: Sequence[str] = (),
        plot: dict[str, Any] | None = None,
    ) -> "CaseResult":
        """What a case's run returns: its description, checks, notes, tables and the
        numbers of its figure (name, family, title and figure filled in by `run_case`)."""
        return cls("", "", "", description, list(checks), None, list(notes), list(tables), plot=dict(plot or {}))

    @property
    def passed(self) -> bool:
        """True when the case ran and every check passed."""
        return self.crashed is None and bool(self.checks) and all(c.passed for c in self.checks)

    def as_dict(self) -> dict:
        """Plain dict (for JSON): everything the page shows (`from_dict` reads it back)."""
        return {
            "name": self.name,
            "family": self.family,
            "title": self.title,
            "passed": self.passed,
            "seconds": self.seconds,
            "crashed": self.crashed,
            "figure": self.figure,
            "checks": [c.as_dict() for c in self.checks],
            "description": self.description,
            "notes": list(self.notes),
            "tables": list(self.tables),
        }

    @classmethod
    def from_dict(cls, d: dict) -> "CaseResult":
        """The result `as_dict` wrote (checks judged again from their numbers; a file
        written before description, notes and tables were stored has none)."""
        checks = [
            Check(c["quantity"], c["unit"], c["reference"], c["source"], c["ours"], c["tolerance"], c["why"], c["kind"])
            for c in d.get("checks", [])
        ]
        return cls(
            d["name"],
            d.get("family", ""),
            d.get("title", d["name"]),
            d.get("description", ""),
            checks,
            d.get("figure"),
            list(d.get("notes", [])),
            list(d.get("tables", [])),
            float(d.get("seconds", 0.0)),
            d.get("crashed"),
        )


@dataclass(frozen=True)
class Case:
    """A registered case: `run(ctx)` computes its checks and returns its CaseResult
    (family, title filled in); `draw(result.plot)` returns its figure (a matplotlib
    Figure), saved as FIGURE_DIR/NAME.png.

    slow: only with `granplate verify --full`.
    """

    name: str
    family: str
    title: str
    run: Callable[["Context"], CaseResult]
    slow: bool = False
    draw: Callable[[dict], Any] | None = None


@dataclass
class Context:
    """What a case may use: the output directory and a run cache (for slow studies);
    figures: draw and save each case's figure (False: the checks only, no matplotlib)."""

    out: Path
    full: bool = False
    run_cache: dict | None = None
    figures: bool = True

    @property
    def figure_dir(self) -> Path:
        path = self.out / FIGURE_DIR
        path.mkdir(parents=True, exist_ok=True)
        return path

    def figure_path(self, name: str) -> Path:
        """Where the figure of case `name` goes."""
        return self.figure_dir / f"{name}.png"


def run_case(case: Case, ctx: Context) -> CaseResult:
    """Run one case and draw its figure (with ctx.figures); an exception becomes a failing
    result carrying the traceback."""
    t0 = time.perf_counter()
    try:
        result = case.run(ctx)
        if ctx.figures and case.draw is not None:
            result.figure = save_figure(case.draw(result.plot), ctx, case.name)
    except Exception:  # noqa: BLE001 - a crashing case is reported, not fatal
        result = CaseResult(case.name, case.family, case.title, crashed=traceback.format_exc())
    result.name, result.family, result.title = case.name, case.family, case.title
    result.seconds = time.perf_counter() - t0
    return result


# --------------------------------------------------------------------------- scenarios


def scenario_text(name: str) -> str:
    """The TOML text of verification scenario `name` (package data)."""
    return (resources.files("granplate.verification") / "scenarios" / f"{name}.toml").read_text(encoding="utf-8")


def scenario_names() -> list[str]:
    """Every verification scenario file, without the .toml suffix."""
    folder = resources.files("granplate.verification") / "scenarios"
    return sorted(p.name[:-5] for p in folder.iterdir() if p.name.endswith(".toml"))


def load_case_scenario(name: str, changes: dict | None = None):
    """The verification scenario `name`, with dotted-path `changes`, validated."""
    from granplate.setup.io import loads, with_changes
    from granplate.setup.validate import validate

    s = loads(scenario_text(name))
    if changes:
        s = with_changes(s, changes)
    validate(s)
    return s


def step_changes(dt: float, t_end: float, out: float | None = None) -> dict:
    """Dotted-path changes setting a fixed step dt, the end time and the output interval
    (the paper scheme, whose step is time.dt_max where criterion (8) does not bind)."""
    out = dt if out is None else out
    return {
        "solver.scheme": "paper",
        "time.dt_max": dt,
        "time.dt_initial": dt,
        "time.dt_min": min(1e-13, dt),
        "time.t_end": t_end,
        "time.output_interval": out,
        "time.field_interval": out,
    }


def simulate(scenario):
    """Run a scenario quietly and return its Dataset."""
    from granplate.results.run import simulate as run

    return run(scenario, progress=False)


# --------------------------------------------------------------------------- numerics


def parabolic_peak(t: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """Time and value of the maximum of samples y(t), refined by a parabola through the
    largest sample and its two neighbours (uniform spacing). Returns (t_peak, y_peak)."""
    k = int(np.argmax(y))
    if k == 0 or k == len(y) - 1:
        return float(t[k]), float(y[k])
    y0, y1, y2 = float(y[k - 1]), float(y[k]), float(y[k + 1])
    den = y0 - 2.0 * y1 + y2
    if den == 0.0:
        return float(t[k]), y1
    p = 0.5 * (y0 - y2) / den
    return float(t[k] + p * (t[k + 1] - t[k])), y1 - 0.25 * (y0 - y2) * p


def last_zero_crossing(t: np.ndarray, y: np.ndarray) -> float:
    """Time where y goes from > 0 to <= 0 for the last time (linear interpolation)."""
    pos = np.flatnonzero(y > 0.0)
    if pos.size == 0 or pos[-1] == len(y) - 1:
        return math.nan
    j = int(pos[-1])
    return float(t[j] + (t[j + 1] - t[j]) * y[j] / (y[j] - y[j + 1]))


def observed_order(e_coarse: float, e_fine: float, ratio: float = 2.0) -> float:
    """log(e_coarse / e_fine) / log(ratio): the order seen when h shrinks by `ratio`."""
    if e_fine == 0.0 or e_coarse == 0.0:
        return math.nan
    return math.log(abs(e_coarse) / abs(e_fine)) / math.log(ratio)


def loglog_slope(x: np.ndarray, y: np.ndarray) -> float:
    """Least-squares slope of log|y| against log x."""
    return float(np.polyfit(np.log(np.asarray(x, float)), np.log(np.abs(np.asarray(y, float))), 1)[0])


def new_figure(ncols: int = 1, nrows: int = 1, width: float = 6.4, height: float = 4.0):
    """A matplotlib figure (Agg backend) and its axes."""
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(
        nrows, ncols, figsize=(width * ncols if ncols > 1 else width, height * nrows), squeeze=False
    )
    return fig, axes


def save_figure(fig, ctx: Context, name: str) -> str:
    """Save and close a figure as FIGURE_DIR/name.png; returns the file name."""
    import matplotlib.pyplot as plt

    fig.tight_layout()
    fig.savefig(ctx.figure_path(name), dpi=110)
    plt.close(fig)
    return f"{name}.png"

"""The report of a study: DIR/report.html, the interactive page (granplate.study.explorer:
the answer first, views linked, plotly.js in DIR/report_assets/), and for papers
DIR/report.md with its figures as PNG and PDF files in DIR/report/ (docs/studies.md).

The figures and the Markdown page hold the study's definition (the study file as run), a
table of the designs, the [report] targets and conclusion when the study has them, the
Pareto front (an optimisation, or a sweep with [objectives]), one figure per metric
against the parameters, heat maps over two grid parameters, the chosen designs (the best
for each objective, with their assembly, energies and stress, re-run in full when their
result was not kept) and the failures with their messages. The Markdown page is rendered
by granplate.results.document, like the reproduction and verification pages.

    >>> from granplate.study.report import write_report
    >>> write_report("q0-r2")          # -> q0-r2/report.html, report.md, report/*.png|pdf
"""

from __future__ import annotations

import dataclasses
import hashlib
import math
import sys
import warnings
from pathlib import Path
from typing import Any

import numpy as np

import granplate as gp
from granplate.results.dataset import scenario_of
from granplate.results.document import Block, to_markdown
from granplate.study import design as D
from granplate.study import plots as P
from granplate.study.outcome import StudyOutcome, read_outcome
from granplate.study.targets import judge

#: The page and its figure folder inside the study's folder.
PAGE = "report.html"
MARKDOWN = "report.md"
FIGURES = "report"
#: Beside the figures: the SHA-256 of the inputs they were drawn from (`inputs_hash`); a
#: report of the same inputs keeps them and draws nothing.
INPUTS_FILE = "inputs.sha256"
#: Metrics of the heat maps and, without [objectives], those whose best design is drawn.
HEADLINE: tuple[str, ...] = ("ep_max_fraction", "max_von_mises", "max_von_mises_disc")
#: Metrics that say how the run went rather than what the design does (figures last).
RUN_METRICS: tuple[str, ...] = ("t_end", "energy_residual_max", "n_steps", "wall_time_s", "compile_time_s")
#: Metrics of the designs table besides the objectives, constraints and targets (the CSV
#: table has them all).
TABLE_METRICS: tuple[str, ...] = (
    "ep_max_fraction",
    "ep_final_fraction",
    "dissipated_fraction",
    "max_von_mises",
    "max_von_mises_disc",
    "max_von_mises_nodes",
    "max_eps_yy",
    "granular_mass",
)
#: Values this small [SI units] are round-off of a quantity that is zero (e_initial of a
#: run from rest): a metric with no larger value is not drawn.
NEGLIGIBLE = 1e-30
#: Most rows of the designs table on the page (results.csv has them all).
MAX_ROWS = 120
#: Figures of a chosen design (granplate.figures.run names) besides its assembly.
DESIGN_FIGURES: tuple[str, ...] = ("energies", "stress-strain", "body-stress")


def fmt(v: Any, unit: str = "") -> str:
    """A value for a table cell: 4 significant digits, Pa shown in MPa."""
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-"
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return str(v)
    factor, _ = P.shown(unit)
    return f"{v * factor:.4g}"


def _head(out: StudyOutcome, name: str) -> str:
    unit = P.shown(out.unit(name))[1]
    return f"{name} [{unit}]"


def shown_metrics(out: StudyOutcome) -> tuple[list[str], list[str]]:
    """(metrics drawn: some design has a value and they are not all equal, run metrics
    last; metrics left out as constant or absent)."""
    drawn, left = [], []
    for m in out.metrics:
        v = np.array(out.metric(m))
        finite = v[np.isfinite(v)]
        varies = finite.size and np.ptp(finite) > 0 and np.max(np.abs(finite)) > NEGLIGIBLE
        (drawn if varies else left).append(m)
    first = list(out.objectives) + list(HEADLINE)
    drawn.sort(key=lambda m: (m in RUN_METRICS, m not in first, first.index(m) if m in first else 0))
    return drawn, left


# ------------------------------------------------------------------------- choices


def directions(out: StudyOutcome) -> dict[str, str]:
    """The objectives, else the headline metrics to minimise (those the study has)."""
    if out.objectives:
        return dict(out.objectives)
    return {m: "minimize" for m in HEADLINE if m in out.metrics}


def candidates(out: StudyOutcome) -> list[int]:
    """Rows that completed with metrics and are feasible (or unconstrained)."""
    return [i for i, r in enumerate(out.rows) if r.ok and r.metrics and r.feasible is not False]


def best_designs(out: StudyOutcome) -> dict[str, int]:
    """metric -> the row of the best feasible design for it (`directions`); none for a
    study judged by targets without objectives (its designs are those of the targets)."""
    best: dict[str, int] = {}
    if out.report.targets and not out.objectives:
        return best
    rows_ = candidates(out)
    for m, way in directions(out).items():
        values = out.metric(m)
        rows = [(v, i) for i in rows_ if math.isfinite(v := float(values[i]))]
        if rows:
            best[m] = (min(rows) if way == "minimize" else max(rows))[1]
    return best


def pareto_front(out: StudyOutcome) -> list[int]:
    """Rows of the feasible designs no other feasible design dominates in the objectives
    (the best one for a single objective); [] without objectives."""
    names = list(out.objectives)
    if not names:
        return []
    sign = np.array([1.0 if out.objectives[n] == "minimize" else -1.0 for n in names])
    values = np.array([out.metric(n) for n in names]).T * sign  # (rows, objectives), all minimised
    rows = [i for i in candidates(out) if np.all(np.isfinite(values[i]))]
    pts = values[rows]
    if len(names) == 2:
        return [rows[k] for k in sorted(_front_2d(pts))]
    return [i for i, p in zip(rows, pts) if not np.any(np.all(pts <= p, axis=1) & np.any(pts < p, axis=1))]


def _front_2d(pts: np.ndarray) -> list[int]:
    """Indices of the points (n, 2), both minimised, that no other point dominates: one
    sweep in the order of the first (O(n log n)); equal points are all kept."""
    order = np.lexsort((pts[:, 1], pts[:, 0]))
    keep, best_before, k = [], math.inf, 0
    while k < len(order):
        group = [order[k]]
        while k + len(group) < len(order) and pts[order[k + len(group)], 0] == pts[order[k], 0]:
            group.append(order[k + len(group)])
        least = pts[group[0], 1]  # the group is sorted by the second objective
        if least < best_before:
            keep += [j for j in group if pts[j, 1] == least]
        best_before = min(best_before, least)
        k += len(group)
    return keep


# ------------------------------------------------------------------------- figures

#: Colours of a report PNG (an adaptive palette: a few times smaller than full colour).
PALETTE = 96


def _png(fig, tmp: Path) -> None:
    """fig as a palette PNG."""
    import io

    from PIL import Image

    buf = io.BytesIO()
    fig.savefig(buf, dpi=P.DPI, format="png")
    image = Image.open(buf).convert("RGB").quantize(PALETTE, method=Image.Quantize.MEDIANCUT)
    image.save(tmp, format="png", optimize=True)


def inputs_hash(out: StudyOutcome) -> str:
    """SHA-256 of everything the report's figures are drawn from: the granplate version,
    the source of the modules that draw them (so that a changed figure is redrawn within a
    version too) and the study as read back (every row's parameters, metrics and status,
    the study file, the folder's name), so equal inputs give equal figures."""
    h = hashlib.sha256(repr((gp.__version__, dataclasses.replace(out, folder=Path(out.folder.name)))).encode())
    for module in (P, sys.modules[__name__]):
        h.update(Path(module.__file__).read_bytes())
    return h.hexdigest()


def stored_hash(fig_dir: Path) -> str:
    """The inputs hash the figures in fig_dir were drawn from ("" when none is stored)."""
    path = fig_dir / INPUTS_FILE
    return path.read_text().strip() if path.is_file() else ""


def _figure(path: Path, make, fresh: bool) -> Path | None:
    """The figure at path (PNG, and PDF beside it for papers): kept as it is when `fresh`
    (drawn from the same inputs) and there, else drawn by make() (None: no such figure)
    and saved."""
    if fresh and path.is_file() and path.with_suffix(".pdf").is_file():
        return path
    fig = make()
    if fig is None:
        return None
    _save_pdf(fig, path.with_suffix(".pdf"))
    return _save(fig, path)


def _save_pdf(fig, path: Path) -> Path:
    """fig as a PDF (no creation date: the same figure gives the same file)."""
    from granplate.store import atomic_write

    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_write(path, lambda tmp: fig.savefig(tmp, format="pdf", metadata={"CreationDate": None}))
    return path


def _save(fig, path: Path) -> Path:
    from granplate.store import atomic_write

    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_write(path, lambda tmp: _png(fig, tmp))
    return path


def design_result(folder: Path, key: str, progress: bool = False):
    """The full result of a design: its kept designs/KEY.nc, else a new run of its
    scenario (the record's scenario_toml; its warnings, which the record holds, not shown
    again); None when it has no record."""
    record = D.read_record(folder, key)
    if record is None:
        return None
    nc = D.record_path(folder, key, ".nc")
    if nc.is_file():
        return gp.read(nc)
    if progress:
        print(f"report: re-running design {key[:12]} for its figures", file=sys.stderr)
    with warnings.catch_warnings():  # what the run warns of is in its record already
        warnings.simplefilter("ignore")
        return gp.simulate(gp.loads(record["scenario_toml"]), progress=False)


def design_figures(folder: Path, key: str, progress: bool = False) -> list[tuple[str, Path]]:
    """(caption, PNG) of a chosen design: its assembly, energies and the plate's stress
    (a 3D body's: body-stress), drawn once (kept in DIR/report/ and reused by the next
    report)."""
    fig_dir = folder / FIGURES
    stem = f"design-{key[:12]}"
    names = ("assembly",) + DESIGN_FIGURES
    existing = [(n, fig_dir / f"{stem}-{n}.png") for n in names if (fig_dir / f"{stem}-{n}.png").is_file()]
    if (fig_dir / f"{stem}-assembly.png").is_file() and (fig_dir / f"{stem}-energies.png").is_file():
        return existing
    ds = design_result(folder, key, progress)
    if ds is None:
        return []
    from granplate.figures import run
    from granplate.figures.drawing import scenario_figure

    drawing, _ = scenario_figure(scenario_of(ds), column=True)
    made = [("assembly", _save(drawing, fig_dir / f"{stem}-assembly.png"))]
    for name, fig in run.figures(ds).items():
        if name in DESIGN_FIGURES:
            made.append((name, _save(fig, fig_dir / f"{stem}-{name}.png")))
    return made


# ------------------------------------------------------------------------- the page


def _definition(out: StudyOutcome) -> list[Block]:
    blocks = [Block("h2", "The study")]
    rows = [("base", out.base or "-", "")]
    rows += [(f"[set] {k}", str(v), out.unit(k)) for k, v in out.fixed.items()]
    rows += [
        (f"parameter {n}", ", ".join(fmt(v, out.unit(n)) for v in P.distinct(out.values(n))), P.shown(out.unit(n))[1])
        for n in out.names
    ]
    rows += [(f"objective {m}", way, P.shown(out.unit(m))[1]) for m, way in out.objectives.items()]
    rows += [("constraint", b.text(out.unit(b.metric)), "") for b in out.constraints]
    blocks.append(Block("table", header=("", "value(s)", "unit"), rows=tuple(rows)))
    if out.study_text:
        blocks.append(Block("p", "The study file as run (`study.toml` in the study's folder):"))
        blocks.append(Block("code", out.study_text))
    return blocks


def same_design(out: StudyOutcome) -> dict[int, int]:
    """row -> the first row of the same design (an optimiser may ask for a design again:
    the same record, the same numbers)."""
    first: dict[str, int] = {}
    return {i: first.setdefault(r.key, i) if r.key else i for i, r in enumerate(out.rows)}


def _with_unit(v: Any, unit: str) -> str:
    """'4000 N/m', '15.3 MPa', 'ptfe' (no unit for a dimensionless or text value)."""
    shown_unit = P.shown(unit)[1]
    text = fmt(v, unit)
    return (
        text if shown_unit == "-" or not isinstance(v, (int, float)) or isinstance(v, bool) else f"{text} {shown_unit}"
    )


def target_designs(out: StudyOutcome) -> list[int]:
    """The rows the targets took in the first combination of choices that meets every
    target ([] without targets, or when none does)."""
    if not out.report.targets:
        return []
    values = [r.metrics if r.ok else {} for r in out.rows]
    for _, verdicts in judge(out.report.targets, out.names, [r.params for r in out.rows], values):
        if all(v.holds for v in verdicts):
            return list(dict.fromkeys(v.design for v in verdicts))
    return []


def chosen_designs(out: StudyOutcome, best: dict[str, int]) -> dict[int, str]:
    """row -> why it is drawn: best for which objectives (directions), or meeting every
    target; each design once."""
    picks: dict[int, list[str]] = {}
    for m, i in best.items():
        picks.setdefault(i, []).append(m)
    out_ = {i: "best " + ", ".join(f"{m} ({directions(out)[m]})" for m in ms) for i, ms in picks.items()}
    for i in target_designs(out):
        out_[i] = (out_[i] + "; " if i in out_ else "") + "meets the targets with the other designs of its combination"
    return out_


def _designs_table(out: StudyOutcome, metrics: list[str], chosen: dict[str, int], front: list[int]) -> Block:
    wanted = (
        set(out.objectives)
        | {b.metric for b in out.constraints}
        | set(TABLE_METRICS)
        | {m for t in out.report.targets for m in t.metrics}
    )
    cols = [m for m in metrics if m in wanted]
    header = ("design",) + tuple(_head(out, n) for n in out.names) + tuple(_head(out, m) for m in cols)
    header += (("feasible",) if out.constraints else ()) + ("status",)
    first = same_design(out)
    marks = {
        i: [f"best {m}" for m, j in chosen.items() if first[j] == i]
        + (["front"] if any(first[j] == i for j in front) else [])
        for i in range(len(out.rows))
    }
    repeats = {i: sum(1 for j in first.values() if j == i) for i in set(first.values())}
    rows = []
    for i, r in enumerate(out.rows):
        if first[i] != i:
            continue  # a trial of a design listed above
        if len(rows) == MAX_ROWS:
            break
        name = (
            str(r.number)
            + (f" (x{repeats[i]} trials)" if repeats[i] > 1 else "")
            + (f" ({', '.join(marks[i])})" if marks[i] else "")
        )
        rows.append(
            (name,)
            + tuple(fmt(r.params.get(n), out.unit(n)) for n in out.names)
            + tuple(fmt(r.metrics.get(m), out.unit(m)) for m in cols)
            + (({True: "yes", False: "no", None: "-"}[r.feasible],) if out.constraints else ())
            + ("ok" if r.ok else "failed" if r.status != "not run" else "not run",)
        )
    return Block("table", header=header, rows=tuple(rows))


def _targets(out: StudyOutcome) -> list[Block]:
    t = out.report
    if not t.targets and not t.conclusion:
        return []
    blocks = [Block("h2", "Targets and conclusion" if t.targets else "Conclusion")]
    if t.targets:
        designs = [r.params for r in out.rows]
        values = [r.metrics if r.ok else {} for r in out.rows]
        rows_ = judge(t.targets, out.names, designs, values)
        keep = list(rows_[0][0]) if rows_ else []
        lines = [
            f"- **{x.label}**: {' or '.join(x.metrics)} within {100 * x.within:.0f}% of "
            f"{fmt(x.value, out.unit(x.metrics[0]))} {P.shown(out.unit(x.metrics[0]))[1]}"
            + (f", for {', '.join(f'{k} = {v}' for k, v in x.where)}" if x.where else "")
            for x in t.targets
        ]
        blocks.append(
            Block(
                "p",
                "Each row is one combination of the choices (the parameters no target "
                "restricts); a target takes the design of the row that matches it, and "
                "holds when its metric (the closest of its alternatives) is within the "
                "tolerance:",
            )
        )
        blocks.append(Block("p", "\n".join(lines)))
        header = tuple(_head(out, n) for n in keep)
        for k in range(len(t.targets)):
            header += (f"target {k + 1}: metric", f"target {k + 1}: value", f"target {k + 1}: holds")
        header += ("result",)
        body, n_all = [], 0
        for params, verdicts in rows_:
            every = all(v.holds for v in verdicts)
            n_all += every
            cells = tuple(fmt(params[n], out.unit(n)) for n in keep)
            for x, v in zip(t.targets, verdicts):
                cells += (
                    v.metric,
                    f"{fmt(v.value, out.unit(v.metric))} {P.shown(out.unit(v.metric))[1]}",
                    {True: "yes", False: "no", None: "-"}[v.holds],
                )
            body.append(cells + ("pass" if every else "FAIL",))
        blocks.append(Block("table", header=header, rows=tuple(body)))
        blocks.append(Block("p", f"**{n_all} of {len(rows_)} combinations meet every target.**"))
    if t.conclusion and t.targets:
        blocks.append(Block("h3", "Conclusion"))
    if t.conclusion:
        for para in t.conclusion.split("\n\n"):
            blocks.append(Block("p", para.strip()))
    return blocks


def _failures(out: StudyOutcome) -> list[Block]:
    bad = [r for r in out.rows if not r.ok]
    blocks = [Block("h2", "Failures")]
    if not bad:
        return blocks + [Block("p", "None: every design ran to its end.")]
    blocks.append(
        Block(
            "p",
            f"{len(bad)} of {len(out.rows)} designs have no result: the message is the "
            'failure\'s (or "not run": not computed yet, rerun the same command).',
        )
    )
    blocks.append(
        Block(
            "table",
            header=("design",) + out.names + ("message",),
            rows=tuple((str(r.number),) + tuple(fmt(r.params.get(n)) for n in out.names) + (r.status,) for r in bad),
        )
    )
    return blocks


def build_report(out: StudyOutcome, progress: bool = False, fresh: bool = False) -> list[Block]:
    """The report's blocks (the Markdown page); its figures are written to DIR/report/ on
    the way (fresh: the figures there were drawn from these same inputs and are kept)."""
    fig_dir = out.folder / FIGURES
    if not fresh:
        _clear_figures(fig_dir)
    blocks = _summary(out)
    blocks += _definition(out)
    drawn, left = shown_metrics(out)
    chosen = best_designs(out)
    front = pareto_front(out)
    blocks += _targets(out)
    blocks += _designs(out, drawn, chosen, front)
    if out.objectives:
        blocks += _pareto(out, front, chosen, fig_dir, fresh)
    blocks += _metrics_against_parameters(out, drawn, left, fig_dir, fresh)
    blocks += _heat_maps(out, drawn, fig_dir, fresh)
    blocks += _chosen(out, chosen, fig_dir, progress)
    blocks += _failures(out)
    return blocks


def _clear_figures(fig_dir: Path) -> None:
    """Remove the figures a report draws again (or that are no longer part of the study)."""
    (fig_dir / INPUTS_FILE).unlink(missing_ok=True)
    for stale in (
        *fig_dir.glob("metric-*.p[nd][gf]"),
        *fig_dir.glob("heatmap-*.p[nd][gf]"),
        fig_dir / "pareto-front.png",
        fig_dir / "pareto-front.pdf",
    ):
        stale.unlink(missing_ok=True)  # drawn again below, or no longer part of the study


def _summary(out: StudyOutcome) -> list[Block]:
    """The title and the counts: designs run, failed, not run, infeasible; how to read it."""
    n_ok = sum(r.ok for r in out.rows)
    n_failed = sum(not r.ok and r.status != "not run" for r in out.rows)
    n_bad = sum(r.feasible is False for r in out.rows)
    what = "optimisation" if out.kind == "optimization" else "sweep"
    blocks = [Block("h1", f"Study report: {out.folder.name} ({what} of {out.base or 'a scenario'})")]
    blocks.append(
        Block(
            "p",
            f"{len(out.rows)} {'trials' if out.kind == 'optimization' else 'designs'}: "
            f"{n_ok} ran, {n_failed} failed, {len(out.rows) - n_ok - n_failed} not run"
            + (f"; {n_bad} infeasible (constraints)" if out.constraints else "")
            + f". Made by granplate {gp.__version__} from the records of granplate "
            f"{out.version or '?'}; the figures are PNG and PDF files in `{FIGURES}/` beside "
            f"this page, the interactive page is `{PAGE}`; the whole table is `{'trials.csv' if out.kind == 'optimization' else 'results.csv'}`."
            " Metrics are those of the run summary (docs/output.md), with their units; Pa "
            "are shown in MPa, dimensionless quantities as [-].",
        )
    )
    return blocks


def _designs(out: StudyOutcome, drawn, chosen, front) -> list[Block]:
    """The designs' table with its introduction."""
    blocks: list[Block] = []
    blocks.append(Block("h2", "Designs"))
    blocks.append(
        Block(
            "p",
            "The main metrics of each design (every metric is in the CSV table)"
            + (f"; the first {MAX_ROWS} designs" if len(out.rows) > MAX_ROWS else "")
            + (
                ". A design the optimiser asked for more than once is listed once, with its first trial"
                if out.kind == "optimization"
                else ""
            )
            + ".",
        )
    )
    blocks.append(_designs_table(out, drawn, chosen, front))
    return blocks


def _pareto(out: StudyOutcome, front, chosen, fig_dir: Path, fresh: bool) -> list[Block]:
    """The Pareto front: its figure and the designs on it."""
    blocks: list[Block] = []
    blocks.append(Block("h2", "Pareto front"))
    path = _figure(fig_dir / "pareto-front.png", lambda: P.fig_pareto(out, front, chosen), fresh)
    if path is not None:
        blocks.append(
            Block(
                "figure",
                "The trials and the Pareto front of the feasible ones"
                + (" (crosses: infeasible)" if out.constraints else "")
                + "; axes in the objectives' units",
                path=path,
            )
        )
    first = same_design(out)
    on_front = list(dict.fromkeys(first[i] for i in front))
    blocks.append(
        Block(
            "p",
            "On the front: "
            + (
                ", ".join(
                    f"{'trial' if out.kind == 'optimization' else 'design'} {out.rows[i].number}"
                    + (
                        f" (and {n - 1} more trials of the same design)"
                        if (n := sum(first[j] == i for j in front)) > 1
                        else ""
                    )
                    for i in on_front
                )
                or "no feasible design"
            )
            + ".",
        )
    )
    return blocks


def _metrics_against_parameters(out: StudyOutcome, drawn, left, fig_dir: Path, fresh: bool) -> list[Block]:
    """Each drawn metric against every parameter, and the metrics not drawn."""
    blocks: list[Block] = []
    blocks.append(Block("h2", "Metrics against the parameters"))
    if left:
        blocks.append(
            Block(
                "p",
                "Not drawn (the same for every design, or no design has it): "
                + ", ".join(f"`{m}`" for m in left)
                + ".",
            )
        )
    for m in drawn:
        blocks.append(
            Block(
                "figure",
                f"{m} [{P.shown(out.unit(m))[1]}] against each parameter",
                path=_figure(fig_dir / f"metric-{m}.png", lambda: P.fig_metric(out, m), fresh),
            )
        )
    return blocks


def _heat_maps(out: StudyOutcome, drawn, fig_dir: Path, fresh: bool) -> list[Block]:
    """Heat maps of the objectives, headline and target metrics over two parameters (none
    when the study has no two to draw them over)."""
    blocks: list[Block] = []
    heat = P.heat_axes(out)
    if heat is not None:
        blocks.append(Block("h2", "Heat maps"))
        blocks.append(
            Block(
                "p",
                f"Over {heat[0]} and {heat[1]}"
                + (f", one panel per value of {', '.join(heat[2])}" if heat[2] else "")
                + ".",
            )
        )
        targets = [m for t in out.report.targets for m in t.metrics]
        for m in dict.fromkeys(list(out.objectives) + list(HEADLINE) + targets):
            if m in drawn:
                path = _figure(fig_dir / f"heatmap-{m}.png", lambda: P.fig_heatmap(out, m), fresh)
                if path is not None:
                    blocks.append(
                        Block("figure", f"{m} [{P.shown(out.unit(m))[1]}] over {heat[0]} and {heat[1]}", path=path)
                    )
    return blocks


def _chosen(out: StudyOutcome, chosen, fig_dir: Path, progress: bool) -> list[Block]:
    """The chosen designs (best per objective or headline metric, the first meeting every
    target) with their metrics and figures; the figures of designs no longer chosen removed."""
    blocks: list[Block] = []
    picks = chosen_designs(out, chosen)
    if picks:
        blocks.append(Block("h2", "Chosen designs"))
        blocks.append(
            Block(
                "p",
                (
                    "the best feasible design for each " + ("objective" if out.objectives else "headline metric")
                    if chosen
                    else ""
                )
                + (
                    ("; " if chosen else "") + "the designs of the first combination that meets every target"
                    if any("meets" in w for w in picks.values())
                    else ""
                )
                + "; their figures are drawn from their full results (re-run when the "
                "study did not keep them, `--full`).",
            )
        )
        intro = blocks[-1].text
        blocks[-1] = Block("p", intro[:1].upper() + intro[1:])
        for i, why in picks.items():
            r = out.rows[i]
            blocks.append(Block("h3", f"Design {r.number}: {why}"))
            metrics = [
                m
                for m in dict.fromkeys(list(directions(out)) + [m for t in out.report.targets for m in t.metrics])
                if m in r.metrics
            ]
            blocks.append(
                Block(
                    "p",
                    ", ".join(f"{n} = {_with_unit(r.params.get(n), out.unit(n))}" for n in out.names)
                    + "; "
                    + ", ".join(f"{m} = {_with_unit(r.metrics.get(m), out.unit(m))}" for m in metrics)
                    + ".",
                )
            )
            for name, path in design_figures(out.folder, r.key, progress):
                blocks.append(Block("figure", f"design {r.number}: {name}", path=path))
    drawn_keys = {out.rows[i].key[:12] for i in picks}
    for old in fig_dir.glob("design-*.png"):  # designs no longer chosen
        if old.name.split("-")[1] not in drawn_keys:
            old.unlink()
    return blocks


def chosen_figures(out: StudyOutcome, progress: bool = False) -> dict[int, list[tuple[str, Path]]]:
    """row -> (caption, PNG) of each chosen design (`chosen_designs`): its figures in
    DIR/report/, drawn when missing (`design_figures`)."""
    picks = chosen_designs(out, best_designs(out))
    return {i: design_figures(out.folder, out.rows[i].key, progress) for i in picks if out.rows[i].key}


def paper_figures(out: StudyOutcome) -> list[Path]:
    """The figures for papers in DIR/report/: PNG and PDF, by name."""
    fig_dir = out.folder / FIGURES
    return sorted(p for p in fig_dir.glob("*.p[nd][gf]") if p.suffix in (".png", ".pdf")) if fig_dir.is_dir() else []


def write_report(folder: str | Path, progress: bool = False, live: bool = False) -> Path:
    """Write DIR/report.html (the interactive page and DIR/report_assets/), DIR/report.md
    and the figures in DIR/report/ (PNG, PDF); the page. live: a sweep read from its
    records (`read_outcome`), for a study that has no table yet."""
    from granplate.store import atomic_write
    from granplate.study.explorer import write_explorer

    out = read_outcome(folder, live=live)
    digest = inputs_hash(out)
    markdown = out.folder / MARKDOWN
    fresh = markdown.is_file() and stored_hash(out.folder / FIGURES) == digest
    blocks = build_report(out, progress, fresh)
    text = to_markdown(blocks, out.folder)
    if not (fresh and markdown.read_text() == text):
        atomic_write(markdown, lambda tmp: tmp.write_text(text))
    if not fresh:
        atomic_write(out.folder / FIGURES / INPUTS_FILE, lambda tmp: tmp.write_text(digest + "\n"))
    return write_explorer(out, chosen_figures(out, progress), paper_figures(out))


def kept_figures(out: StudyOutcome) -> dict[int, list[tuple[str, Path]]]:
    """row -> (caption, PNG) of each chosen design whose figures are already in
    DIR/report/ (nothing drawn, nothing re-run)."""
    return {
        i: [
            (n, p)
            for n in ("assembly",) + DESIGN_FIGURES
            if (p := out.folder / FIGURES / f"design-{out.rows[i].key[:12]}-{n}.png").is_file()
        ]
        for i in chosen_designs(out, best_designs(out))
        if out.rows[i].key
    }


def write_live_page(folder: str | Path, live: bool = True) -> tuple[Path, dict[str, int]]:
    """The interactive page of a study while it runs: its designs as their records
    arrive, no figure drawn, reloading itself while designs are left (live; not: the page
    as it stands, without the reload); (page, counts)."""
    from granplate.study.explorer import counts, write_explorer

    out = read_outcome(folder, live=True)
    return write_explorer(out, kept_figures(out), paper_figures(out), live=live), counts(out)

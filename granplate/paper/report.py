"""The reproduction report: our numbers beside the paper's (docs/model.md section 8).

The report opens on its verdicts (`verdict_summary`: statements that hold, that do
not, reported without a verdict; the paper's conclusions). The comparison table is
`granplate.paper.statements` judged on the result Datasets
(one Check per statement: the paper's value, ours, their ratio, the verdict and the
criterion's own text); `granplate.paper.discussion` explains the disagreements with the
sensitivity runs of `granplate.paper.checks`. `write_report` renders the table, the run
table, the discussion, the figures and the animations to report.md and a
self-contained report.html (PNGs embedded) through granplate.results.document.

    >>> rows = statements({"bare-plate": ds0, "steel-r1": ds1, ...})
    >>> rows[0].ours_text, rows[0].holds
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from granplate.paper import checks as ck
from granplate.paper import plastic
from granplate.paper import space as sp
from granplate.paper.discussion import (
    intensity_discussion,
    ptfe_discussion,
    stress_discussion,
    vertical_discussion,
)
from granplate.paper.statements import Results, e_shock as _e_shock, max_von_mises as _max_vm, statements
from granplate.results import analysis as an
from granplate.results.criteria import Check
from granplate.results.document import Block, details, summary, to_html, to_markdown

__all__ = ["statements", "run_rows", "conclusions", "verdict_summary", "build_report", "load_results", "write_report"]


def _pct(x: float) -> str:
    return f"{100 * x:.1f}%"


def run_rows(results: Results, records: dict[str, object] | None = None) -> list[list[str]]:
    """One row per run: E_shock, plate shares, max stress (Gauss-point peak and disc average,
    "-" for a result written before the latter existed), the largest Hertz peak pressure
    p0 and its ratio to the yield onset 1.6 Y (of the material pair with the largest
    ratio, named; "-" without contacts), residual, steps, wall time."""
    rows = []
    for name, ds in results.items():
        info = an.run_info(ds)
        share = an.plate_share(ds)
        rec = (records or {}).get(name)
        rows.append(
            [
                name,
                f"{float(ds['time'].values[-1]) * 1e3:.3g}",
                f"{_e_shock(ds):.3e}",
                _pct(share["peak"]),
                _pct(share["final"]),
                f"{_max_vm(ds) / 1e6:.1f}",
                f"{float(ds['max_von_mises_disc'].max()) / 1e6:.1f}" if "max_von_mises_disc" in ds else "-",
                f"{float(ds['max_eps_yy'].max()):.2e}" if "max_eps_yy" in ds else "-",
                *plastic.pressure_cells(ds),
                f"{an.max_energy_residual(ds):.1e}",
                f"{int(info.get('n_steps', 0)):,}",
                f"{float(info.get('wall_time_s', float('nan'))):.1f}",
                getattr(rec, "status", "-"),
            ]
        )
    return rows


RUN_HEADER = [
    "run",
    "t_end [ms]",
    "E_shock [J]",
    "plate peak",
    "plate at t_end",
    "max von Mises [MPa]",
    "disc-averaged von Mises [MPa]",
    "max abs(eps_yy)",
    "largest p0 [MPa] (pair)",
    "p0 / (1.6 Y)",
    "max abs(energy residual)",
    "time steps",
    "wall time [s]",
    "this time",
]


# --------------------------------------------------------------------------------------
# Rendering
# --------------------------------------------------------------------------------------
#: The paper's qualitative conclusions and the rows that show them.
CONCLUSIONS: tuple[tuple[str, tuple[str, ...]], ...] = (
    (
        "With granules, the max von Mises stress and the energy put in are far below the bare plate's",
        ("vm_reduction", "energy_reduction"),
    ),
    (
        "PTFE intruders let a much smaller share of the shock reach the plate than steel ones, and keep "
        "the energy in column 1",
        ("ptfe_vs_steel", "column_one"),
    ),
    ("The plate's share grows with the shock intensity", ("intensity_peak", "intensity_mean")),
)


def conclusion_verdicts(rows: list[Check]) -> list[tuple[str, bool | None, list[int]]]:
    """Per conclusion of the paper: its text, whether it holds (None: not run) and the
    numbers (from 1) of the rows that show it."""
    by_key = {r.key: (i, r) for i, r in enumerate(rows) if r.key}
    out = []
    for text, keys in CONCLUSIONS:
        found = [by_key[k] for k in keys if k in by_key]
        verdicts = [r.holds for _, r in found]
        holds = None if not found or any(v is None for v in verdicts) else all(verdicts)
        out.append((text, holds, [i + 1 for i, _ in found]))
    return out


def conclusions(rows: list[Check]) -> list[str]:
    """One line per conclusion of the paper: holds / does not hold / not run, from the rows."""
    lines = []
    for text, holds, numbers in conclusion_verdicts(rows):
        word = "not run" if holds is None else "**holds**" if holds else "**does not hold**"
        lines.append(f"{text}: {word} (rows {', '.join(f'#{i}' for i in numbers)}).")
    return lines


def _holds(h: bool | None) -> str:
    return "yes" if h is True else "no" if h is False else "-"


def _ratio(r: float | None) -> str:
    return "-" if r is None or not np.isfinite(r) else f"{r:.2f}"


def verdict_summary(
    rows: list[Check], results: Results, checks: Results, twins: Results | None = None, space: Results | None = None
) -> Block:
    """The first screen: statements that hold, that do not, reported without a verdict;
    the conclusions that hold; the runs behind them (the yielding-contact and 3D twins too)."""
    n_ok = sum(r.holds is True for r in rows)
    n_bad = sum(r.holds is False for r in rows)
    n_reported = len(rows) - n_ok - n_bad
    verdicts = [holds for _, holds, _ in conclusion_verdicts(rows)]
    n_concl = sum(h is True for h in verdicts)
    headline = (
        f"{n_ok} of {n_ok + n_bad} judged statements hold"
        + (f", {n_bad} do not" if n_bad else "")
        + f"; {n_concl} of {len(verdicts)} of the paper's conclusions hold."
    )
    n_runs = len(results) + len(checks or {}) + len(twins or {}) + len(space or {})
    return summary(
        headline,
        [
            (str(n_ok), "statements hold", "yes" if n_ok else ""),
            (str(n_bad), "do not hold", "no" if n_bad else "yes"),
            (str(n_reported), "reported without a verdict", ""),
            (f"{n_concl} / {len(verdicts)}", "conclusions hold", "yes" if n_concl == len(verdicts) else "no"),
            (str(n_runs), "runs", ""),
        ],
    )


def build_report(
    results: Results,
    checks: Results,
    *,
    records: dict[str, object] | None = None,
    figures: dict[str, list[Path]] | None = None,
    animations: list[Path] | None = None,
    seconds: float | None = None,
    twins: Results | None = None,
    space: Results | None = None,
    measured: Results | None = None,
) -> list[Block]:
    """The report as blocks: summary, comparison table, runs, discussion, the cases with
    yielding contacts (twins: preset name -> the Thornton twin's Dataset; none: no section;
    measured: the twins under the law that matches measurement, plastic.MEASURED_LAW), the
    cases in 3D (space: preset name -> its 3D twin's Dataset; none: no section), figures."""
    rows = statements(results)
    blocks = [
        Block("h1", "granplate: reproduction of the paper's section 3 and appendices"),
        verdict_summary(rows, results, checks, twins, space),
        _introduction(rows, results, checks, twins, space, measured, seconds),
    ]
    blocks += _statements(rows)
    blocks += _runs(results, checks, records, twins)
    blocks += _differences(results, checks)
    blocks += plastic.section(
        results, twins or {}, measured=measured, records=records, figure=(figures or {}).get(plastic.FIGURE_KEY)
    )
    blocks += sp.section(results, space or {}, records=records, figure=(figures or {}).get(sp.FIGURE_KEY))
    blocks += _figures_and_animations(figures, animations)
    return blocks


def _introduction(rows, results: Results, checks: Results, twins, space, measured, seconds) -> Block:
    """What the report was made from (runs, checks, twins), how many judged statements hold,
    and a warning when the runs were shortened."""
    from granplate.version import __version__

    judged = [r for r in rows if r.holds is not None]
    n_ok = sum(r.holds for r in judged)
    t_ends = sorted({float(d["time"].values[-1]) for d in results.values()})
    intro = (
        f"Made by granplate {__version__} from {len(results)} runs"
        + (f" and {len(checks)} check runs" if checks else "")
        + (f", {len(twins)} of them rerun with yielding contacts" if twins else "")
        + (f" (and again with the law {plastic.MEASURED_LAW!r})" if twins and measured else "")
        + (f", {len(space)} of them run again in 3D" if space else "")
        + (
            f" (this reproduce took {seconds:.0f} s; each run's own wall time is in the run table)"
            if seconds is not None
            else ""
        )
        + ". "
        f"{n_ok} of {len(judged)} judged statements hold. Every 'ours' value below is computed from the "
        f"result files by `granplate.report`; the paper's values are from its text (docs/model.md section 8)."
    )
    if t_ends and max(t_ends) < 2e-3 * 0.999:
        intro += (
            f" **The runs were shortened (t_end = {max(t_ends) * 1e3:.3g} ms instead of 2 ms): the "
            f"comparison with the paper is not meaningful.**"
        )
    return Block("p", intro)


def _statements(rows) -> list[Block]:
    """The paper's conclusions in our runs, the statements that do not hold, and the table
    of the paper's statements beside ours."""
    blocks: list[Block] = []
    blocks.append(Block("h2", "The paper's conclusions in our runs"))
    blocks.append(Block("p", "\n".join(f"- {line}" for line in conclusions(rows))))
    failing = [f"{i + 1} ({r.quantity})" for i, r in enumerate(rows) if r.holds is False]
    if failing:
        blocks.append(
            Block(
                "p", "Statements that do not hold: " + "; ".join(failing) + ". Each is discussed below the run tables."
            )
        )
    blocks.append(Block("h2", "The paper's statements and ours"))
    blocks.append(
        Block(
            "table",
            header=("#", "statement", "paper", "ours", "ratio", "holds", "criterion", "where"),
            rows=tuple(
                (
                    str(i + 1),
                    r.quantity,
                    r.reference_text,
                    r.ours_text,
                    _ratio(r.ratio),
                    _holds(r.holds),
                    r.rule,
                    r.source,
                )
                for i, r in enumerate(rows)
            ),
        )
    )
    return blocks


def _runs(results: Results, checks: Results, records, twins) -> list[Block]:
    """The run table, the contact pressures per material pair, the check runs (collapsed)."""
    blocks: list[Block] = []
    blocks.append(Block("h2", "Runs"))
    blocks.append(
        Block(
            "p",
            "Energy residual: max over the run of |E_p + E_g + D - E_shock| / E_shock (eq. 11). "
            "Wall time: the simulation itself, as recorded in the result; 'this time': whether "
            "this reproduce ran it or reused the stored result.",
        )
    )
    blocks.append(Block("table", header=tuple(RUN_HEADER), rows=tuple(tuple(r) for r in run_rows(results, records))))
    pairs = plastic.pair_rows(results)
    if pairs:
        blocks.append(
            Block(
                "p",
                "Contact pressures per material pair: the largest Hertz peak pressure p0 = "
                "(2/pi) E* sqrt(delta/R*) over the pair's contacts and the run, and its ratio to "
                "the yield onset 1.6 Y of the body that yields (docs/model.md eqs. P1-P2; walls and "
                "the plate's face are rigid: the granule's Y). Past 1, the elastic law is outside "
                "its validity"
                + (
                    ": the section 'Contacts that yield' reruns the cases with yielding contacts."
                    if twins
                    else " (`granplate reproduce` without `--no-plastic` reruns the cases with yielding contacts)."
                ),
            )
        )
        blocks.append(Block("table", header=plastic.PAIR_HEADER, rows=tuple(pairs)))
    if checks:
        blocks.append(
            details(
                f"Check runs (sensitivity, see the discussion): {len(checks)} runs",
                [Block("table", header=tuple(RUN_HEADER), rows=tuple(tuple(r) for r in run_rows(checks, records)))],
            )
        )
    return blocks


def _differences(results: Results, checks: Results) -> list[Block]:
    """Where we differ from the paper, and why: stress, PTFE, intensity, vertical motion."""
    blocks: list[Block] = []
    blocks.append(Block("h2", "Where we differ from the paper, and why"))
    for para in (
        stress_discussion(results, checks)
        + ptfe_discussion(results, checks)
        + intensity_discussion(results)
        + vertical_discussion(results)
    ):
        blocks.append(Block("p", para))
    return blocks


def _figures_and_animations(figures, animations) -> list[Block]:
    """Each paper figure drawn (its PNG), and the animations."""
    from granplate.paper.plots import FIGURES, figure_stem

    blocks: list[Block] = []
    if figures:
        blocks.append(Block("h2", "Figures"))
        for key in FIGURES:
            if key in figures:
                png = [p for p in figures[key] if Path(p).suffix == ".png"]
                if png:
                    blocks.append(
                        Block(
                            "figure",
                            f"Fig. {key}: {FIGURES[key].title} ({figure_stem(key)}.png / .pdf)",
                            path=Path(png[0]),
                        )
                    )
    if animations:
        blocks.append(Block("h2", "Animations (Appendix B, displacements x125)"))
        for a in animations:
            blocks.append(Block("media", Path(a).stem, path=Path(a)))
    return blocks


def load_results(paths: dict[str, Path]) -> Results:
    """Read result files (name -> path) into Datasets, skipping unreadable ones."""
    from granplate.results.dataset import read

    out: Results = {}
    for name, p in paths.items():
        try:
            out[name] = read(p)
        except Exception:  # noqa: BLE001 - a missing or partial file is left out of the report
            continue
    return out


def write_report(out_dir: str | Path, outcome) -> list[Path]:
    """Write out_dir/report.md and out_dir/report.html for a reproduce outcome.

    outcome: anything with .runs (RunRecord: name, path, status, kind; kind "plastic": a
    preset's twin with Thornton's yielding contacts, "johnson": with the law "johnson",
    "space": its 3D twin), .figures
    (key -> paths), .animations (paths) and .seconds.
    """
    from granplate.setup.presets import preset_names

    out = Path(out_dir)
    done = [r for r in outcome.runs if r.status in ("ran", "reused")]
    order = {n: i for i, n in enumerate(preset_names())}
    presets = {
        r.name: r.path for r in sorted((r for r in done if r.kind == "preset"), key=lambda r: order.get(r.name, 99))
    }
    check_paths = {r.name: r.path for r in done if r.kind == "check"}
    check_paths = {c.name: check_paths[c.name] for c in ck.CHECKS if c.name in check_paths}
    twin_paths = {plastic.twin_preset(r.name): r.path for r in done if r.kind == plastic.TWIN_DIR}
    twin_paths = {n: twin_paths[n] for n in preset_names() if n in twin_paths}
    law_dir = plastic.TWIN_LAWS[plastic.MEASURED_LAW]
    measured_paths = {plastic.twin_preset(r.name): r.path for r in done if r.kind == law_dir}
    measured = load_results({n: measured_paths[n] for n in preset_names() if n in measured_paths})
    space_paths = {sp.twin_preset(r.name): r.path for r in done if r.kind == "space"}
    space_paths = {n: space_paths[n] for n in preset_names() if n in space_paths}
    results, checks, twins = load_results(presets), load_results(check_paths), load_results(twin_paths)
    space = load_results(space_paths)
    records = {r.name: r for r in outcome.runs}
    blocks = build_report(
        results,
        checks,
        records=records,
        figures=outcome.figures,
        animations=outcome.animations,
        seconds=getattr(outcome, "seconds", None),
        twins=twins,
        measured=measured,
        space=space,
    )
    md, page = out / "report.md", out / "report.html"
    md.write_text(to_markdown(blocks, out))
    page.write_text(to_html(blocks, out))
    return [md, page]

"""The paper's six cases in 3D: the presets' 3D twins and the report's section "The
paper in 3D".

A 3D twin is preset NAME as the preset `3d-NAME` (`granplate.setup.presets.twin_3d`,
docs/model.md section 8.1): the same packing in the plane z = 0 against a 3D slab of the
paper's plate (hex20, one element through the thickness), the rigid layers as
translation-only strips on the slab's face, the same line load, velocity Verlet at a
fixed step. Every preset has one, the bare plate too.

`granplate reproduce --3d` runs the twins beside the presets (`DIR/3d/NAME.nc`) and
`section` sets both sets of results side by side: a table case by case (2D / 3D, every
number `granplate.summary` of the two result files), each case's E_shock and peak plate
share judged against the thin-limit targets (TARGETS, as `Check`s of
granplate.results.criteria), the twins' run table and the figure.

    >>> twins = {n: gp.simulate(twin_scenario(n)) for n in twin_presets()}
    >>> blocks = section(plane_results, twins)
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from granplate.paper.statements import Results
from granplate.results.criteria import Check, Within
from granplate.results.dataset import summary
from granplate.results.document import Block, details

#: Folder of the twins' results under reproduce's output directory, and the prefix of
#: their run names ("3d/steel-r1").
TWIN_DIR = "3d"

#: Key of the section's figure among the products of `granplate reproduce` (fig-3d).
FIGURE_KEY = "3d"

#: Where the thin-limit targets and the causes of the differences are written down.
SOURCE = "docs/model.md section 8.1"


@dataclass(frozen=True)
class Target:
    """A thin-limit target: a number of `summary` (key), its words, its unit, and how
    far (relative) the 3D twin's may be from the 2D run's."""

    key: str
    quantity: str
    unit: str
    tol: float

    @property
    def criterion(self) -> Within:
        return Within(self.tol, name=self.quantity, against="the 2D run's")


#: The thin-limit targets the differences are judged against (the full runs of
#: docs/model.md section 8.1 stay within 0.07% and 1%).
TARGETS: tuple[Target, ...] = (
    Target("e_shock", "E_shock", "J", 0.01),
    Target("ep_max_fraction", "plate peak share", "-", 0.02),
)


def twin_name(preset: str) -> str:
    """The run name of a preset's 3D twin: "3d/NAME"."""
    return f"{TWIN_DIR}/{preset}"


def twin_preset(name: str) -> str | None:
    """The preset a twin's run name stands for (None for a name that is not a twin's)."""
    head, _, tail = name.partition("/")
    return tail if head == TWIN_DIR and tail else None


def twin_presets() -> list[str]:
    """The presets that get a 3D twin: all six, in preset order."""
    from granplate.setup.presets import preset_names

    return preset_names()


def twin_scenario(name: str, t_end: float | None = None):
    """The 3D twin of preset `name` (the preset "3d-NAME"), shortened to t_end [s] when given."""
    from granplate.paper.reproduce import shortened
    from granplate.setup.presets import preset

    return shortened(preset("3d-" + name), t_end)


# --------------------------------------------------------------------------------------
# Numbers, from the result files
# --------------------------------------------------------------------------------------
def case_rows(results: Results, twins: Results) -> list[dict]:
    """One record per case with a 3D twin, in the order of `results`: case, and the
    `summary` of its 2D ("plane") and 3D ("space") results."""
    return [{"case": n, "plane": summary(ds), "space": summary(twins[n])} for n, ds in results.items() if n in twins]


def difference(plane: float | None, space: float | None) -> float | None:
    """(3D - 2D) / 2D; None where either is missing or the 2D value is 0."""
    if plane is None or space is None or plane == 0.0:
        return None
    return (float(space) - float(plane)) / float(plane)


def thin_limit_checks(results: Results, twins: Results) -> list[tuple[str, Check]]:
    """Per case and target (TARGETS): (case, the Check of the 3D value against the 2D one
    under the target's criterion), in the order of `results`. The Check's verdict is
    the criterion's (none where either value is missing); its ratio is 3D / 2D."""
    out = []
    for c in case_rows(results, twins):
        for t in TARGETS:
            a, b = c["plane"][t.key], c["space"][t.key]
            out.append(
                (
                    c["case"],
                    Check(
                        quantity=t.quantity,
                        unit=t.unit,
                        reference=a,
                        source=SOURCE,
                        ours=b,
                        criterion=t.criterion,
                        judged=a is not None,
                        reference_text=_value(a, t.key),
                        ours_text=_value(b, t.key),
                        ratio=None if a in (None, 0.0) or b is None else b / a,
                        key=f"{c['case']}:{t.key}",
                    ),
                )
            )
    return out


# --------------------------------------------------------------------------------------
# Text
# --------------------------------------------------------------------------------------
def _value(x: float | None, key: str) -> str:
    if x is None:
        return "-"
    return f"{100 * x:#.4g}%" if key.endswith("fraction") else f"{x:.4e}"


def _diff(x: float | None) -> str:
    """A relative difference in percent, signed ("0.00%" where it rounds to nothing)."""
    if x is None:
        return "-"
    text = f"{100 * x:+.2f}%"
    return "0.00%" if text in ("+0.00%", "-0.00%") else text


def _both(a: str, b: str) -> str:
    return f"{a} / {b}"


def _mpa(x: float | None) -> str:
    return "-" if x is None else f"{x / 1e6:.1f}"


def _ratio(a: float | None, b: float | None) -> str:
    return "-" if not a or b is None else f"{b / a:.1f}"


CASE_HEADER = (
    "case",
    "E_shock 2D / 3D [J]",
    "E_shock 3D vs 2D",
    "plate peak 2D / 3D",
    "plate peak 3D vs 2D",
    "max von Mises 2D / 3D [MPa]",
    "max abs(energy residual) 2D / 3D",
    "wall time 2D / 3D [s]",
    "wall time 3D / 2D",
)


def case_table(results: Results, twins: Results) -> list[tuple[str, ...]]:
    """The section's table: per case, 2D / 3D and the relative differences, from
    `summary` of each result."""
    rows = []
    for c in case_rows(results, twins):
        a, b = c["plane"], c["space"]
        rows.append(
            (
                c["case"],
                _both(_value(a["e_shock"], "e_shock"), _value(b["e_shock"], "e_shock")),
                _diff(difference(a["e_shock"], b["e_shock"])),
                _both(_value(a["ep_max_fraction"], "ep_max_fraction"), _value(b["ep_max_fraction"], "ep_max_fraction")),
                _diff(difference(a["ep_max_fraction"], b["ep_max_fraction"])),
                _both(_mpa(a["max_von_mises"]), _mpa(b["max_von_mises"])),
                _both(f"{a['energy_residual_max']:.1e}", f"{b['energy_residual_max']:.1e}"),
                _both(f"{a['wall_time_s']:.1f}", f"{b['wall_time_s']:.1f}"),
                _ratio(a["wall_time_s"], b["wall_time_s"]),
            )
        )
    return rows


CHECK_HEADER = ("#", "case", "quantity", "2D", "3D", "3D vs 2D", "target", "holds")


def _holds(h: bool | None) -> str:
    return "yes" if h is True else "no" if h is False else "-"


def check_table(checks: list[tuple[str, Check]]) -> list[tuple[str, ...]]:
    """One row per case and target: both values, the difference, the target's text and
    the verdict."""
    return [
        (
            str(i + 1),
            case,
            c.quantity,
            c.reference_text,
            c.ours_text,
            _diff(difference(c.reference, c.ours)),
            c.rule,
            _holds(c.holds),
        )
        for i, (case, c) in enumerate(checks)
    ]


def verdict_text(checks: list[tuple[str, Check]]) -> str:
    """A paragraph: how many differences are within their targets, and which are not."""
    n_ok = sum(c.holds is True for _, c in checks)
    missed = [
        f"{case} {c.quantity} ({_diff(difference(c.reference, c.ours))})" for case, c in checks if c.holds is False
    ]
    unjudged = [f"{case} {c.quantity}" for case, c in checks if c.holds is None]
    targets = ", ".join(f"{t.quantity} within {100 * t.tol:g}%" for t in TARGETS)
    text = (
        f"**{n_ok} of {len(checks)} differences are within the thin-limit targets** ({targets} of the 2D "
        f"run's; {SOURCE})."
    )
    if missed:
        text += " Outside them: " + "; ".join(missed) + "."
    if unjudged:
        text += " Not judged (a value missing): " + "; ".join(unjudged) + "."
    return text


def choices_text() -> str:
    """What the 3D twins are."""
    return (
        "Each case is run again in space as its preset's 3D twin (`granplate preset 3d-NAME`, "
        f"{SOURCE}): the same packing of spheres in the plane z = 0, the paper's plate as a 3D slab of hex20 "
        "elements (one through its 1 mm thickness) clamped on ymin and ymax, the rigid layers as "
        "translation-only strips across the thickness tying only the face the granules touch, the same line "
        "load (on each loaded granule its 2D resultants; on the bare plate a traction on the slab's face), "
        "velocity Verlet at a fixed step (0.2 us for the steel packings, 0.4 to 0.5 us where the contacts "
        "allow it) and the slab's modes below a cut-off with the residual "
        "compliance at the contacts. Everything else is the preset's. In the thin limit the 3D twin should "
        "give the 2D run's numbers; the table sets them side by side, each cell 2D / 3D, computed by "
        "`granplate.summary` from both result files. Wall time: the run's own as recorded in the result (the "
        "model's set-up and the time loop; building and writing the result file not included)."
    )


def causes_text() -> str:
    """Where the differences between 2D and 3D come from (docs/model.md section 8.1)."""
    return (
        "Where the differences come from: E_shock, because velocity Verlet samples the load at its kicks "
        "(50 per pulse at 0.2 us, 20 at 0.5 us: the difference grows as the step squared) where the 2D "
        "implicit scheme integrates it "
        "adaptively; the plate's energy, because the 3D slab is not the plane-stress plate (its in-plane "
        "modes lie 0.2% above the plane-stress plate's) and because the rigid layers tie only the slab's face "
        "(a patch that also tied the side faces stiffened the slab and cut the PTFE case's peak share by "
        "10%). The largest von Mises stress of the bare plate differs more: at the loaded face's clamped "
        "corners plane stress is singular and the slab's stress there is not the plane's. Wall times: the "
        "2D runs integrate implicitly with an adaptive step, the 3D twins explicitly at a fixed step, so "
        f"their ratio is the cost of going to space at these settings, not a benchmark ({SOURCE})."
    )


def section(
    results: Results,
    twins: Results,
    *,
    records: dict[str, object] | None = None,
    figure: list[Path] | None = None,
) -> list[Block]:
    """The report section "The paper in 3D": what the twins are, the table case by case
    (2D / 3D), the thin-limit verdicts, where the differences come from, the twins' run
    table and the figure (its PNG and PDF paths, when drawn). Empty when there are no twins."""
    from granplate.paper.report import RUN_HEADER, run_rows

    if not twins:
        return []
    checks = thin_limit_checks(results, twins)
    blocks = [Block("h2", "The paper in 3D"), Block("p", choices_text())]
    t_ends = [float(d["time"].values[-1]) for d in twins.values()]
    if t_ends and max(t_ends) < 2e-3 * 0.999:
        blocks.append(
            Block(
                "p",
                f"**The 3D twins were shortened (t_end = {max(t_ends) * 1e3:.3g} ms instead of "
                f"2 ms): the thin-limit targets are set for full runs.**",
            )
        )
    blocks.append(Block("table", header=CASE_HEADER, rows=tuple(case_table(results, twins))))
    blocks.append(Block("p", verdict_text(checks)))
    blocks.append(Block("table", header=CHECK_HEADER, rows=tuple(check_table(checks))))
    blocks.append(Block("p", causes_text()))
    named = {twin_name(n): ds for n, ds in twins.items()}
    blocks.append(
        details(
            f"The 3D twins' runs: {len(named)} runs",
            [Block("table", header=tuple(RUN_HEADER), rows=tuple(tuple(r) for r in run_rows(named, records)))],
        )
    )
    png = [p for p in (figure or []) if Path(p).suffix == ".png"]
    if png:
        blocks.append(
            Block(
                "figure",
                f"The plate's share of the shock energy, each case in 2D (solid) and 3D "
                f"(dashed) ({Path(png[0]).stem}.png / .pdf)",
                path=Path(png[0]),
            )
        )
    return blocks

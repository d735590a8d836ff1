"""The paper's six cases re-examined with yielding contacts: the plastic twins and the
report's section "Contacts that yield".

A twin is a preset run again with one change, `contact.normal_law = "thornton"`
(Thornton's elastic-perfectly plastic law, docs/model.md section 3.6), on every material
pair, with the built-in materials as they are (granplate.setup.materials: `steel` S355,
`ptfe`). Walls and the plate's face are rigid bodies to the law, so at a granule-wall or
granule-plate contact the granule yields (its Y). The bare plate has no contacts: it is
its own twin (its elastic result stands in both columns, it is not run again).

`granplate reproduce` runs the twins beside the presets (`DIR/plastic/NAME.nc`) and
`section` turns both sets of results into report blocks: a table case by case, elastic
vs yielding (computed by `granplate.summary` from the result files), the same statement
checks of `granplate.paper.statements` judged on the twins, side by side with the
elastic verdicts, and the contact pressures per material pair.

    >>> twins = {n: gp.simulate(twin_scenario(n)) for n in twin_presets()}
    >>> blocks = section(elastic_results, twins)
"""

from __future__ import annotations

from pathlib import Path

import xarray as xr

from granplate.paper.statements import Results, statements
from granplate.results.criteria import Check
from granplate.results.dataset import pair_table, scenario_of, summary
from granplate.results.document import Block

#: Folder of the twins' results under reproduce's output directory, and the prefix of
#: their run names ("plastic/steel-r1").
TWIN_DIR = "plastic"

#: The one change a twin makes to its preset (dotted path -> value).
TWIN_CHANGES: dict[str, object] = {"contact.normal_law": "thornton"}

#: The case the section's figure shows, elastic against yielding (the PTFE headline case).
FIGURE_CASE = "ptfe-r05"

#: Key of the section's figure among the products of `granplate reproduce`.
FIGURE_KEY = "yielding"


def twin_name(preset: str) -> str:
    """The run name of a preset's twin: "plastic/NAME"."""
    return f"{TWIN_DIR}/{preset}"


def twin_preset(name: str) -> str | None:
    """The preset a twin's run name stands for (None for a name that is not a twin's)."""
    head, _, tail = name.partition("/")
    return tail if head == TWIN_DIR and tail else None


def has_contacts(scenario) -> bool:
    """Whether a scenario has granules (so contacts a normal law acts on)."""
    return scenario.layout is not None or bool(scenario.granules)


def twin_presets() -> list[str]:
    """The presets that get a twin: those with granules, in preset order (the bare plate
    has no contacts and is its own twin)."""
    from granplate.setup.presets import preset, preset_names

    return [n for n in preset_names() if has_contacts(preset(n))]


def twin_scenario(name: str, t_end: float | None = None):
    """Preset `name` with yielding contacts (TWIN_CHANGES), shortened to t_end [s] when given."""
    from granplate.paper.reproduce import shortened
    from granplate.setup.io import with_changes
    from granplate.setup.presets import preset

    return shortened(with_changes(preset(name), TWIN_CHANGES), t_end)


# --------------------------------------------------------------------------------------
# Numbers, from the result files
# --------------------------------------------------------------------------------------
def worst_pair(ds: xr.Dataset) -> dict | None:
    """The material pair whose largest Hertz peak pressure came closest to (or went
    furthest past) its yield onset: the row of `pair_table` with the largest
    p0 / (1.6 Y); None when the result has no pair with a known Y."""
    rows = [r for r in pair_table(ds) if r["yield_onset_ratio"] is not None]
    return max(rows, key=lambda r: r["yield_onset_ratio"]) if rows else None


def case_rows(results: Results, twins: Results) -> list[dict]:
    """One record per case with a twin (or without contacts: its own twin), in the order
    of `results`: name, own_twin (bool), and the elastic and yielding `summary` of each."""
    out = []
    for name, ds in results.items():
        own = not _has_granules(ds) and name not in twins
        twin = ds if own else twins.get(name)
        if twin is None:
            continue
        out.append({"case": name, "own_twin": own, "elastic": summary(ds), "yielding": summary(twin)})
    return out


def _has_granules(ds: xr.Dataset) -> bool:
    """Whether a result has granules (a bare plate's has none)."""
    return ds.sizes.get("granule", 0) > 0


def twin_results(results: Results, twins: Results) -> Results:
    """The results the statements are judged on with yielding contacts: the twins, and
    each case without contacts as itself (the bare plate), in the order of `results`."""
    out: Results = {}
    for name, ds in results.items():
        if name in twins:
            out[name] = twins[name]
        elif not _has_granules(ds):
            out[name] = ds
    return out


def statement_pairs(results: Results, twins: Results) -> list[tuple[Check, Check]]:
    """The paper's statements judged on the elastic results and on the twins (the same
    `statements` machinery), paired by statement, in the elastic table's order."""
    elastic = statements(results)
    yielding = {r.key or r.quantity: r for r in statements(twin_results(results, twins))}
    return [(r, yielding[r.key or r.quantity]) for r in elastic if (r.key or r.quantity) in yielding]


def movement(elastic: bool | None, yielding: bool | None) -> str:
    """What becomes of a verdict with yielding contacts: "still holds", "no longer holds",
    "now holds", "still does not hold", or "-" where either is not judged."""
    if elastic is None or yielding is None:
        return "-"
    if elastic == yielding:
        return "still holds" if elastic else "still does not hold"
    return "now holds" if yielding else "no longer holds"


# --------------------------------------------------------------------------------------
# Text
# --------------------------------------------------------------------------------------
def _pct(x: float | None) -> str:
    return "-" if x is None else f"{100 * x:.1f}%"


def _mpa(x: float | None) -> str:
    return "-" if x is None else f"{x / 1e6:.1f}"


def _both(a: str, b: str) -> str:
    return f"{a} / {b}"


def _ratio_text(ds: xr.Dataset) -> str:
    """The largest p0 / (1.6 Y) of a run and its pair, e.g. "2.69 (steel-steel)"; "-"
    for a run without contacts or Y."""
    w = worst_pair(ds)
    return "-" if w is None else f"{w['yield_onset_ratio']:.2f} ({w['pair']})"


def pressure_cells(ds: xr.Dataset) -> list[str]:
    """The run table's two cells of a run: its largest p0 [MPa] and p0 / (1.6 Y), of the
    pair with the largest ratio (named), "-" for a run without contacts."""
    w = worst_pair(ds)
    if w is None:
        return ["-", "-"]
    return [f"{w['max_contact_pressure'] / 1e6:.1f} ({w['pair']})", f"{w['yield_onset_ratio']:.2f}"]


PAIR_HEADER = (
    "run",
    "material pair",
    "normal law",
    "Y [MPa]",
    "largest p0 [MPa]",
    "p0 / (1.6 Y)",
    "at t [ms]",
    "contact",
)


def pair_rows(results: Results) -> list[tuple[str, ...]]:
    """One row per run and material pair: the law, Y of the body that yields, the largest
    Hertz peak pressure p0 and its ratio to the yield onset 1.6 Y, when and where."""
    rows = []
    for name, ds in results.items():
        for r in pair_table(ds):
            y, ratio = r["yield_strength"], r["yield_onset_ratio"]
            rows.append(
                (
                    name,
                    r["pair"],
                    r["normal_law"],
                    _mpa(y),
                    _mpa(r["max_contact_pressure"]),
                    "-" if ratio is None else f"{ratio:.2f}",
                    f"{r['time'] * 1e3:.3f}",
                    r["contact"],
                )
            )
    return rows


CASE_HEADER = (
    "case",
    "E_shock [J]",
    "plate peak",
    "plate at t_end",
    "max von Mises [MPa]",
    "disc-averaged von Mises [MPa]",
    "D_plastic / E_shock",
    "largest p0 / (1.6 Y)",
)


def case_table(results: Results, twins: Results) -> list[tuple[str, ...]]:
    """The section's table: per case, elastic / yielding, from `summary` of each result."""
    rows = []
    for c in case_rows(results, twins):
        e, y = c["elastic"], c["yielding"]
        el_ds, pl_ds = results[c["case"]], (results if c["own_twin"] else twins)[c["case"]]
        rows.append(
            (
                c["case"] + (" (its own twin)" if c["own_twin"] else ""),
                _both(f"{e['e_shock']:.3e}", f"{y['e_shock']:.3e}"),
                _both(_pct(e["ep_max_fraction"]), _pct(y["ep_max_fraction"])),
                _both(_pct(e["ep_final_fraction"]), _pct(y["ep_final_fraction"])),
                _both(_mpa(e["max_von_mises"]), _mpa(y["max_von_mises"])),
                _both(_mpa(e["max_von_mises_disc"]), _mpa(y["max_von_mises_disc"])),
                _pct(y["plastic_fraction"]),
                _both(_ratio_text(el_ds), _ratio_text(pl_ds)),
            )
        )
    return rows


STATEMENT_HEADER = (
    "#",
    "statement",
    "ours, elastic",
    "holds (elastic)",
    "ours, yielding",
    "holds (yielding)",
    "with yielding contacts",
)


def _holds(h: bool | None) -> str:
    return "yes" if h is True else "no" if h is False else "-"


def statement_table(pairs: list[tuple[Check, Check]]) -> list[tuple[str, ...]]:
    """The statements side by side: ours and the verdict, elastic and yielding, and what moved."""
    return [
        (str(i + 1), e.quantity, e.ours_text, _holds(e.holds), y.ours_text, _holds(y.holds), movement(e.holds, y.holds))
        for i, (e, y) in enumerate(pairs)
    ]


def _granule_materials(ds: xr.Dataset) -> list[str]:
    """The materials of a result's granules."""
    return sorted({str(m) for m in ds["material"].values}) if "material" in ds else []


def choices_text(twins: Results) -> str:
    """What the twins are: the law, the materials and their Y (read from the twins'
    scenarios), the rigid walls and plate face, the bare plate as its own twin."""
    mats: dict[str, float | None] = {}
    for ds in twins.values():
        s = scenario_of(ds)
        for n in _granule_materials(ds):
            mats[n] = s.material(n).Y
    stated = ", ".join(
        f"`{n}` Y = {_mpa(y)} MPa" if y is not None else f"`{n}` (Y unknown)" for n, y in sorted(mats.items())
    )
    return (
        f'Each case with granules is run again with `contact.normal_law = "thornton"` (Thornton\'s '
        f"elastic-perfectly plastic law, docs/model.md section 3.6) on every contact and the built-in "
        f"materials as they are: granules {stated} (`steel` is a structural S355, `ptfe` unfilled PTFE; "
        f"docs/model.md section 2). Walls and the plate's face are rigid bodies to the law: at a "
        f"granule-wall or granule-plate contact the granule yields, at its own Y. Everything else is the "
        f"preset's (damping, friction, plate, time step). The bare plate has no contacts: it is its own "
        f"twin (its elastic result stands in both columns; it is not run again). "
        f"p0 is the largest Hertz peak pressure (2/pi) E* sqrt(delta/R*) over a pair's contacts, from "
        f"each contact's largest overlap (eq. P2); 1.6 Y is the onset of yield (eq. P1). Past 1 in an "
        f"elastic run, its contacts are outside the Hertz law's validity; in a yielding run the ratio "
        f"says how far past the onset the largest overlap went. Shares are of the energy put in, "
        f"E_shock (the presets start at rest)."
    )


def _list(names: list[str]) -> str:
    return "; ".join(names) if names else "none"


def verdict_text(pairs: list[tuple[Check, Check]]) -> str:
    """A paragraph: how many judged statements still hold, and which ones move."""
    moves: dict[str, list[str]] = {}
    for i, (e, y) in enumerate(pairs):
        moves.setdefault(movement(e.holds, y.holds), []).append(f"#{i + 1} {e.quantity}")
    judged = sum(len(v) for k, v in moves.items() if k != "-")
    count = {k: len(moves.get(k, [])) for k in ("still holds", "still does not hold", "no longer holds", "now holds")}
    return (
        f"Of the {judged} statements judged both ways: still hold {count['still holds']}, still do not hold "
        f"{count['still does not hold']}; with yielding contacts, no longer hold {count['no longer holds']} "
        f"({_list(moves.get('no longer holds', []))}), now hold {count['now holds']} "
        f"({_list(moves.get('now holds', []))}). The verdicts are the comparison table's criteria judged on "
        f"the twins' results."
    )


def section(
    results: Results,
    twins: Results,
    *,
    records: dict[str, object] | None = None,
    figure: list[Path] | None = None,
) -> list[Block]:
    """The report section "Contacts that yield": the choices, the table case by case
    (elastic / yielding), the paper's conclusions and statements judged on the twins
    beside the elastic verdicts, the twins' run table, the contact pressures per
    material pair and the figure (its PNG and PDF paths, when drawn). Empty when there
    are no twins."""
    from granplate.paper.report import RUN_HEADER, conclusions, run_rows

    if not twins:
        return []
    pairs = statement_pairs(results, twins)
    blocks = [Block("h2", "Contacts that yield"), Block("p", choices_text(twins))]
    t_ends = [float(d["time"].values[-1]) for d in twins.values()]
    if t_ends and max(t_ends) < 2e-3 * 0.999:
        blocks.append(Block("p", f"**The twins were shortened (t_end = {max(t_ends) * 1e3:.3g} ms instead of 2 ms).**"))
    blocks.append(
        Block(
            "p",
            "Case by case; each cell: elastic / yielding contacts, computed by `granplate.summary` "
            "from both result files. D_plastic: the plastic work of the yielding run by t_end "
            "(eq. 11).",
        )
    )
    blocks.append(Block("table", header=CASE_HEADER, rows=tuple(case_table(results, twins))))
    blocks.append(Block("h3", "The paper's conclusions with yielding contacts"))
    blocks.append(Block("p", "\n".join(f"- {line}" for line in conclusions([y for _, y in pairs]))))
    blocks.append(Block("p", verdict_text(pairs)))
    blocks.append(Block("table", header=STATEMENT_HEADER, rows=tuple(statement_table(pairs))))
    named = {twin_name(n): ds for n, ds in twins.items()}
    blocks.append(Block("h3", "The twins' runs"))
    blocks.append(Block("table", header=tuple(RUN_HEADER), rows=tuple(tuple(r) for r in run_rows(named, records))))
    blocks.append(Block("p", "Contact pressures per material pair, elastic runs and their twins:"))
    both = {}
    for name, ds in results.items():
        both[name] = ds
        if name in twins:
            both[twin_name(name)] = twins[name]
    blocks.append(Block("table", header=PAIR_HEADER, rows=tuple(pair_rows(both))))
    png = [p for p in (figure or []) if Path(p).suffix == ".png"]
    if png:
        blocks.append(
            Block(
                "figure",
                f"The plate's energy and where the shock energy goes, {FIGURE_CASE} with "
                f"elastic and yielding contacts ({Path(png[0]).stem}.png / .pdf)",
                path=Path(png[0]),
            )
        )
    return blocks

"""The paper's six cases re-examined with yielding contacts: the plastic twins and the
report's section "Contacts that yield".

A twin is a preset run again with one change, its normal law, on every material pair,
with the built-in materials as they are (granplate.setup.materials: `steel` S355,
`ptfe`). Two families of twins: `contact.normal_law = "thornton"` (Thornton's
elastic-perfectly plastic law, docs/model.md section 3.6; `DIR/plastic/NAME.nc`) and
`"johnson"` (the law held against measured sphere compressions, section 3.10;
`DIR/johnson/NAME.nc`). Walls and the plate's face are rigid bodies to the laws, so at a
granule-wall or granule-plate contact the granule yields (its Y). The bare plate has no
contacts: it is its own twin (its elastic result stands in every column, it is not run
again).

`granplate reproduce` runs the twins beside the presets and `section` turns the sets of
results into report blocks: a table case by case, elastic vs each law (computed by
`granplate.summary` from the result files), the same statement checks of
`granplate.paper.statements` judged on the twins, side by side with the elastic verdicts,
and the contact pressures per material pair.

    >>> twins = {n: gp.simulate(twin_scenario(n)) for n in twin_presets()}
    >>> measured = {n: gp.simulate(twin_scenario(n, law="johnson")) for n in twin_presets()}
    >>> blocks = section(elastic_results, twins, measured=measured)
"""

from __future__ import annotations

from pathlib import Path

import xarray as xr

from granplate.paper.statements import Results, statements
from granplate.results.criteria import Check
from granplate.results.dataset import pair_table, scenario_of, summary
from granplate.results.document import Block

#: The twins' normal laws -> the folder of their results under reproduce's output
#: directory, which is also the prefix of their run names ("plastic/steel-r1") and their
#: runs' kind: Thornton's law (the first, the default) and the law that matches measurement.
TWIN_LAWS: dict[str, str] = {"thornton": "plastic", "johnson": "johnson"}

#: Folder of Thornton's twins (TWIN_LAWS["thornton"]).
TWIN_DIR = TWIN_LAWS["thornton"]

#: The law of the twins held against measurement (docs/validation.md, yield-measured).
MEASURED_LAW = "johnson"

#: The one change a Thornton twin makes to its preset (dotted path -> value).
TWIN_CHANGES: dict[str, object] = {"contact.normal_law": "thornton"}

#: The case the section's figure shows, elastic against yielding (the PTFE headline case).
FIGURE_CASE = "ptfe-r05"

#: Key of the section's figure among the products of `granplate reproduce`.
FIGURE_KEY = "yielding"


def twin_name(preset: str, law: str = "thornton") -> str:
    """The run name of a preset's twin under `law`: "plastic/NAME" (Thornton), "johnson/NAME"."""
    return f"{TWIN_LAWS[law]}/{preset}"


def twin_preset(name: str) -> str | None:
    """The preset a twin's run name stands for (None for a name that is not a twin's)."""
    head, _, tail = name.partition("/")
    return tail if head in TWIN_LAWS.values() and tail else None


def has_contacts(scenario) -> bool:
    """Whether a scenario has granules (so contacts a normal law acts on)."""
    return scenario.layout is not None or bool(scenario.granules)


def twin_presets() -> list[str]:
    """The presets that get a twin: those with granules, in preset order (the bare plate
    has no contacts and is its own twin)."""
    from granplate.setup.presets import preset, preset_names

    return [n for n in preset_names() if has_contacts(preset(n))]


def twin_scenario(name: str, t_end: float | None = None, law: str = "thornton"):
    """Preset `name` with yielding contacts (contact.normal_law = law), shortened to t_end
    [s] when given."""
    from granplate.paper.reproduce import shortened
    from granplate.setup.io import with_changes
    from granplate.setup.presets import preset

    if law not in TWIN_LAWS:
        raise ValueError(f"no twins of the normal law {law!r}; allowed: {', '.join(TWIN_LAWS)}")
    return shortened(with_changes(preset(name), {"contact.normal_law": law}), t_end)


# --------------------------------------------------------------------------------------
# Numbers, from the result files
# --------------------------------------------------------------------------------------
def worst_pair(ds: xr.Dataset) -> dict | None:
    """The material pair whose largest Hertz peak pressure came closest to (or went
    furthest past) its yield onset: the row of `pair_table` with the largest
    p0 / (1.6 Y); None when the result has no pair with a known Y."""
    rows = [r for r in pair_table(ds) if r["yield_onset_ratio"] is not None]
    return max(rows, key=lambda r: r["yield_onset_ratio"]) if rows else None


def case_rows(results: Results, twins: Results, measured: Results | None = None) -> list[dict]:
    """One record per case with a twin (or without contacts: its own twin), in the order
    of `results`: name, own_twin (bool), and the elastic and yielding `summary` of each
    (and "measured": the summary of its twin under MEASURED_LAW, where `measured` has one)."""
    out = []
    for name, ds in results.items():
        own = not _has_granules(ds) and name not in twins
        twin = ds if own else twins.get(name)
        if twin is None:
            continue
        row = {"case": name, "own_twin": own, "elastic": summary(ds), "yielding": summary(twin)}
        if measured:
            m = ds if own else measured.get(name)
            row["measured"] = summary(m) if m is not None else None
        out.append(row)
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


def statement_triples(results: Results, twins: Results, measured: Results) -> list[tuple[Check, Check, Check]]:
    """The statements judged elastic, on Thornton's twins and on the twins of MEASURED_LAW,
    by statement, in the elastic table's order (those judged on all three sets)."""
    third = {r.key or r.quantity: r for r in statements(twin_results(results, measured))}
    return [
        (e, y, third[e.key or e.quantity]) for e, y in statement_pairs(results, twins) if (e.key or e.quantity) in third
    ]


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


def _both(*cells: str) -> str:
    return " / ".join(cells)


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


def case_table(results: Results, twins: Results, measured: Results | None = None) -> list[tuple[str, ...]]:
    """The section's table: per case, elastic / Thornton (/ MEASURED_LAW, where `measured`
    holds the case), from `summary` of each result."""
    rows = []
    for c in case_rows(results, twins, measured):
        runs = [c["elastic"], c["yielding"]] + ([c["measured"]] if c.get("measured") else [])
        own = c["own_twin"]
        sets = [results, results if own else twins] + ([results if own else measured] if c.get("measured") else [])
        dsets = [d[c["case"]] for d in sets if d is not None]
        rows.append(
            (
                c["case"] + (" (its own twin)" if own else ""),
                _both(*(f"{r['e_shock']:.3e}" for r in runs)),
                _both(*(_pct(r["ep_max_fraction"]) for r in runs)),
                _both(*(_pct(r["ep_final_fraction"]) for r in runs)),
                _both(*(_mpa(r["max_von_mises"]) for r in runs)),
                _both(*(_mpa(r["max_von_mises_disc"]) for r in runs)),
                _both(*(_pct(r["plastic_fraction"]) for r in runs[1:])),
                _both(*(_ratio_text(d) for d in dsets)),
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


TRIPLE_HEADER = (
    "#",
    "statement",
    "ours, elastic",
    "holds (elastic)",
    "ours, thornton",
    "holds (thornton)",
    f"ours, {MEASURED_LAW}",
    f"holds ({MEASURED_LAW})",
    f"with {MEASURED_LAW} contacts",
)


def triple_table(triples: list[tuple[Check, Check, Check]]) -> list[tuple[str, ...]]:
    """The statements judged three ways: ours and the verdict, elastic, Thornton's and
    MEASURED_LAW's, and what moved from elastic to MEASURED_LAW."""
    return [
        (
            str(i + 1),
            e.quantity,
            e.ours_text,
            _holds(e.holds),
            y.ours_text,
            _holds(y.holds),
            m.ours_text,
            _holds(m.holds),
            movement(e.holds, m.holds),
        )
        for i, (e, y, m) in enumerate(triples)
    ]


def _granule_materials(ds: xr.Dataset) -> list[str]:
    """The materials of a result's granules."""
    return sorted({str(m) for m in ds["material"].values}) if "material" in ds else []


def choices_text(twins: Results, measured: Results | None = None) -> str:
    """What the twins are: the laws, the materials and their Y (read from the twins'
    scenarios), the rigid walls and plate face, the bare plate as its own twin."""
    mats: dict[str, float | None] = {}
    for ds in [*twins.values(), *(measured or {}).values()]:
        s = scenario_of(ds)
        for n in _granule_materials(ds):
            mats[n] = s.material(n).Y
    stated = ", ".join(
        f"`{n}` Y = {_mpa(y)} MPa" if y is not None else f"`{n}` (Y unknown)" for n, y in sorted(mats.items())
    )
    laws = (
        'Each case with granules is run again with `contact.normal_law = "thornton"` (Thornton\'s '
        "elastic-perfectly plastic law, docs/model.md section 3.6)"
    )
    if measured:
        laws += (
            f' and again with `contact.normal_law = "{MEASURED_LAW}"` (Hertz to yield, then Johnson\'s '
            "expanding-cavity pressure over the flattened disc up to Tabor's hardness 2.8 Y, section 3.10: "
            "the law held against Burgoyne & Daraio's measured compressions of metal spheres, whose loading "
            "slopes Thornton's law underestimates 3 to 5 times; docs/validation.md, yield-measured; rate-free "
            "here, as these materials give no rate coefficient)"
        )
    return (
        f"{laws}, on every contact and the built-in "
        f"materials as they are: granules {stated} (`steel` is a structural S355, `ptfe` unfilled PTFE; "
        f"docs/model.md section 2). Walls and the plate's face are rigid bodies to the laws: at a "
        f"granule-wall or granule-plate contact the granule yields, at its own Y. Everything else is the "
        f"preset's (damping, friction, plate, time step). The bare plate has no contacts: it is its own "
        f"twin (its elastic result stands in every column; it is not run again). "
        f"p0 is the largest Hertz peak pressure (2/pi) E* sqrt(delta/R*) over a pair's contacts, from "
        f"each contact's largest overlap (eq. P2); 1.6 Y is the onset of yield (eq. P1). Past 1 in an "
        f"elastic run, its contacts are outside the Hertz law's validity; in a yielding run the ratio "
        f"says how far past the onset the largest overlap went. Shares are of the energy put in, "
        f"E_shock (the presets start at rest)."
    )


def _list(names: list[str]) -> str:
    return "; ".join(names) if names else "none"


def _moves_of(pairs: list[tuple[Check, Check]]) -> str:
    """What moves with a law's twins, in short: "no longer hold N (...), now hold M (...)."."""
    moves: dict[str, list[str]] = {}
    for i, (e, y) in enumerate(pairs):
        moves.setdefault(movement(e.holds, y.holds), []).append(f"#{i + 1}")
    lost, won = moves.get("no longer holds", []), moves.get("now holds", [])
    return f"no longer hold {len(lost)} ({_list(lost)}), now hold {len(won)} ({_list(won)})."


def verdict_text(pairs: list[tuple[Check, Check]], law: str = "thornton") -> str:
    """A paragraph: how many judged statements still hold, and which ones move, with the
    twins of normal law `law`."""
    moves: dict[str, list[str]] = {}
    for i, (e, y) in enumerate(pairs):
        moves.setdefault(movement(e.holds, y.holds), []).append(f"#{i + 1} {e.quantity}")
    judged = sum(len(v) for k, v in moves.items() if k != "-")
    count = {k: len(moves.get(k, [])) for k in ("still holds", "still does not hold", "no longer holds", "now holds")}
    return (
        f"Of the {judged} statements judged both ways: still hold {count['still holds']}, still do not hold "
        f"{count['still does not hold']}; with yielding contacts ({law}), no longer hold {count['no longer holds']} "
        f"({_list(moves.get('no longer holds', []))}), now hold {count['now holds']} "
        f"({_list(moves.get('now holds', []))}). The verdicts are the comparison table's criteria judged on "
        f"the twins' results."
    )


def section(
    results: Results,
    twins: Results,
    *,
    measured: Results | None = None,
    records: dict[str, object] | None = None,
    figure: list[Path] | None = None,
) -> list[Block]:
    """The report section "Contacts that yield": the choices, the table case by case
    (elastic / Thornton / MEASURED_LAW), the paper's conclusions and statements judged on
    the twins beside the elastic verdicts (the conclusions with the law that matches
    measurement, where its twins ran), the twins' run table, the contact pressures per
    material pair and the figure (its PNG and PDF paths, when drawn). Empty when there are
    no twins."""
    from granplate.paper.report import RUN_HEADER, conclusions, run_rows

    if not twins:
        return []
    measured = measured or {}
    pairs = statement_pairs(results, twins)
    blocks = [Block("h2", "Contacts that yield"), Block("p", choices_text(twins, measured))]
    t_ends = [float(d["time"].values[-1]) for d in [*twins.values(), *measured.values()]]
    if t_ends and max(t_ends) < 2e-3 * 0.999:
        blocks.append(Block("p", f"**The twins were shortened (t_end = {max(t_ends) * 1e3:.3g} ms instead of 2 ms).**"))
    cells = f"elastic / thornton / {MEASURED_LAW}" if measured else "elastic / yielding contacts"
    blocks.append(
        Block(
            "p",
            f"Case by case; each cell: {cells}, computed by `granplate.summary` from the result files. "
            "D_plastic: the plastic work of the yielding runs by t_end (eq. 11).",
        )
    )
    blocks.append(Block("table", header=CASE_HEADER, rows=tuple(case_table(results, twins, measured))))
    blocks += _verdict_blocks(results, twins, measured, pairs, conclusions)
    named = {twin_name(n): ds for n, ds in twins.items()}
    named.update({twin_name(n, MEASURED_LAW): ds for n, ds in measured.items()})
    blocks.append(Block("h3", "The twins' runs"))
    blocks.append(Block("table", header=tuple(RUN_HEADER), rows=tuple(tuple(r) for r in run_rows(named, records))))
    blocks.append(Block("p", "Contact pressures per material pair, elastic runs and their twins:"))
    every = {}
    for name, ds in results.items():
        every[name] = ds
        for law, runs in (("thornton", twins), (MEASURED_LAW, measured)):
            if name in runs:
                every[twin_name(name, law)] = runs[name]
    blocks.append(Block("table", header=PAIR_HEADER, rows=tuple(pair_rows(every))))
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


def _verdict_blocks(results: Results, twins: Results, measured: Results, pairs, conclusions) -> list[Block]:
    """The paper's conclusions and statements with yielding contacts: judged on the twins of
    MEASURED_LAW beside Thornton's and the elastic verdicts where those ran, else on
    Thornton's twins."""
    if not measured:
        return [
            Block("h3", "The paper's conclusions with yielding contacts"),
            Block("p", "\n".join(f"- {line}" for line in conclusions([y for _, y in pairs]))),
            Block("p", verdict_text(pairs)),
            Block("table", header=STATEMENT_HEADER, rows=tuple(statement_table(pairs))),
        ]
    triples = statement_triples(results, twins, measured)
    by_law = [(e, m) for e, _, m in triples]
    return [
        Block("h3", "The paper's conclusions with the law that matches measurement"),
        Block("p", "\n".join(f"- {line}" for line in conclusions([m for _, _, m in triples]))),
        Block(
            "p",
            verdict_text(by_law, MEASURED_LAW).replace(
                " The verdicts", " Under Thornton's law: " + _moves_of(pairs) + " The verdicts"
            ),
        ),
        Block("table", header=TRIPLE_HEADER, rows=tuple(triple_table(triples))),
    ]

"""The intruder map with elastic contacts against its twins with contacts that yield,
computed from the committed tables (docs/studies/intruder-map/results.csv against
docs/studies/intruder-map-plastic/results.csv, Thornton's law, or
docs/studies/intruder-map-johnson/results.csv, the law "johnson"): the comparisons of
docs/studies.md, "The intruder map with contacts that yield", printed as the Markdown that
page shows.

    python docs/studies/compare-intruder-maps.py            # Thornton's law
    python docs/studies/compare-intruder-maps.py johnson    # the law "johnson"

Nothing is run: the numbers are the tables'. Fractions are of the shock's work e_in
(docs/output.md), shown in percent; stresses in MPa.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pandas as pd

HERE = Path(__file__).resolve().parent
ELASTIC = HERE / "intruder-map" / "results.csv"
PLASTIC = HERE / "intruder-map-plastic" / "results.csv"
#: The yielding twins' tables by normal law, and how the text names the law.
TWINS = {"thornton": PLASTIC, "johnson": HERE / "intruder-map-johnson" / "results.csv"}
LAW_NAMES = {"thornton": "Thornton's law", "johnson": 'the law "johnson"'}
#: The varied parameters (in the study files' order) and the columns compared.
KEYS = ["layout.R2_ratio", "layout.intruder_material", "load.q0"]
MATERIALS = ["steel", "aluminium", "ptfe"]
#: The smallest radius ratio, sqrt(2) - 1: columns 1 and 3 touch.
SMALLEST = 0.4142136


def read_tables(elastic: Path = ELASTIC, plastic: Path = PLASTIC) -> pd.DataFrame:
    """The two tables side by side, one row per design (matched on the parameters):
    each metric as `NAME_e` (elastic) and `NAME_p` (yielding)."""
    e, p = pd.read_csv(elastic), pd.read_csv(plastic)
    for table, path in ((e, elastic), (p, plastic)):
        bad = table[table["status"] != "ok"]
        if len(bad):
            raise ValueError(f"{path}: designs {list(bad['design'])} did not complete")
    both = e.merge(p, on=KEYS, suffixes=("_e", "_p"), validate="one_to_one")
    if len(both) != len(e) or len(both) != len(p):
        raise ValueError("the two tables do not hold the same designs")
    return both


def pct(x: float) -> str:
    """A fraction in percent, one decimal."""
    return f"{100.0 * x:.1f}%"


def span(values, fmt=pct) -> str:
    """'lo to hi' of some values."""
    lo, hi = min(values), max(values)
    return fmt(lo) if fmt(lo) == fmt(hi) else f"{fmt(lo)} to {fmt(hi)}"


def mpa(x: float) -> str:
    """A stress [Pa] in MPa, one decimal."""
    return f"{x * 1e-6:.1f} MPa"


def ratio(x: float) -> str:
    """A dimensionless ratio, two decimals."""
    return f"{x:.2f}"


def share_table(t: pd.DataFrame) -> list[str]:
    """The plate's peak share per radius ratio and load, elastic -> yielding, per material."""
    head = "| R2/R1 | q0 [kN/m] | " + " | ".join(f"{m}: elastic -> yielding" for m in MATERIALS) + " |"
    lines = [head, "|" + "---|" * (2 + len(MATERIALS))]
    for (ratio, q0), g in t.groupby(["layout.R2_ratio", "load.q0"], sort=True):
        g = g.set_index("layout.intruder_material")
        cells = [f"{pct(g.loc[m, 'ep_max_fraction_e'])} -> {pct(g.loc[m, 'ep_max_fraction_p'])}" for m in MATERIALS]
        lines.append(f"| {ratio:.2f} | {q0 * 1e-3:g} | " + " | ".join(cells) + " |")
    return lines


def best(t: pd.DataFrame, metric: str, suffix: str, q0: float) -> pd.Series:
    """The design of least `metric` at the load q0 in one table ("_e" or "_p")."""
    g = t[t["load.q0"] == q0]
    return g.loc[g[metric + suffix].idxmin()]


def design_name(row: pd.Series) -> str:
    return f"{row['layout.intruder_material']} R2/R1 = {row['layout.R2_ratio']:.2f}"


def facts(t: pd.DataFrame, law: str = "thornton") -> list[str]:
    """The comparison's findings, one Markdown bullet each, every number from the tables
    (the twin's normal law `law` named in the text)."""
    out = []
    loads = sorted(t["load.q0"].unique())
    passed = t[t["yield_onset_ratio_e"] > 1.0]
    below = t[t["yield_onset_ratio_e"] <= 1.0]
    metrics = ("ep_max_fraction", "max_von_mises", "dissipated_fraction", "n_steps")
    same = all((below[f"{m}_e"] == below[f"{m}_p"]).all() for m in metrics)
    close = all(((below[f"{m}_e"] - below[f"{m}_p"]).abs() <= 1e-9 * below[f"{m}_e"].abs()).all() for m in metrics)
    alike = "the same, to the last digit," if same else "the same to round-off (1e-9)" if close else "not the same"
    below_names = sorted(below["layout.R2_ratio"].unique())
    kept_peak = (passed["ep_max_fraction_p"] / passed["ep_max_fraction_e"] - 1.0).abs() < 1e-3
    out.append(
        f"**Yield in the elastic map.** {len(passed)} of its {len(t)} designs press some "
        f"contact past the yield onset p0 = 1.6 Y (`yield_onset_ratio` "
        f"{span(t['yield_onset_ratio_e'], ratio)}); the {len(below)} that do not "
        f"({'/'.join(sorted(below['layout.intruder_material'].unique()))} intruders of R2/R1 = "
        f"{', '.join(f'{r:.2f}' for r in below_names)} at "
        f"{', '.join(f'{q * 1e-3:g}' for q in sorted(below['load.q0'].unique()))} kN/m) are "
        f"{alike} in the twin: {LAW_NAMES[law]} "
        f"is Hertz's below p_y. Of the {len(passed)} that yield, {int(kept_peak.sum())} keep their "
        f"plate's peak share within 0.1%: they yield after that peak."
    )
    top = t[t["load.q0"] == loads[-1]]
    per_load = ", ".join(f"{span(t.loc[t['load.q0'] == q, 'plastic_fraction_p'])} at {q * 1e-3:g} kN/m" for q in loads)
    out.append(
        f"**Plastic work.** The share of the shock's work spent yielding contacts "
        f"(`plastic_fraction`) is {per_load}. At {loads[-1] * 1e-3:g} kN/m the dissipated share "
        f"(`dissipated_fraction`, plastic work included) is {span(top['dissipated_fraction_p'])}, "
        f"against {span(top['dissipated_fraction_e'])} with elastic contacts."
    )
    columns = t.sort_values("load.q0").groupby(["layout.R2_ratio", "layout.intruder_material"])
    first, last = columns.first(), columns.last()
    grows_e = last["ep_max_fraction_e"] > first["ep_max_fraction_e"]
    falls_p = last["ep_max_fraction_p"] < first["ep_max_fraction_p"]
    is_ptfe = first.index.get_level_values("layout.intruder_material") == "ptfe"
    big = first.index.get_level_values("layout.R2_ratio") > SMALLEST
    top_heavy = top[top["layout.intruder_material"] != "ptfe"]
    out.append(
        f"**The share against the shock.** Elastic, the plate's peak "
        f"share is larger at {loads[-1] * 1e-3:g} than at {loads[0] * 1e-3:g} kN/m for "
        f"{int(grows_e.sum())} of the {len(grows_e)} radius-material combinations of the map; "
        f"yielding, it is smaller for {int(falls_p[~(is_ptfe & big)].sum())} of the "
        f"{int((~(is_ptfe & big)).sum())} with steel or aluminium intruders or the smallest ones "
        f"(R2/R1 = {SMALLEST:.2f}), and still larger for {int((~falls_p[is_ptfe & big]).sum())} of "
        f"the {int((is_ptfe & big).sum())} with larger PTFE intruders. "
        f"At {loads[-1] * 1e-3:g} kN/m steel and aluminium intruders pass "
        f"{span(top_heavy['ep_max_fraction_p'])} instead of {span(top_heavy['ep_max_fraction_e'])}, "
        f"the plate's largest stress {span(top_heavy['max_von_mises_p'], mpa)} instead of "
        f"{span(top_heavy['max_von_mises_e'], mpa)}."
    )
    ptfe = t[(t["layout.intruder_material"] == "ptfe") & (t["layout.R2_ratio"] > SMALLEST)]
    steel = t[t["layout.intruder_material"] == "steel"]
    paired = ptfe.merge(steel, on=["layout.R2_ratio", "load.q0"], suffixes=("", "_steel"))
    paired = paired[paired["load.q0"] == loads[-1]]
    to_steel_e = paired["ep_max_fraction_e"] / paired["ep_max_fraction_e_steel"]
    to_steel_p = paired["ep_max_fraction_p"] / paired["ep_max_fraction_p_steel"]
    lighter = t[t["layout.R2_ratio"] > SMALLEST]
    least = all(
        g.loc[g["layout.intruder_material"] == "ptfe", "ep_max_fraction_p"].iloc[0]
        < g.loc[g["layout.intruder_material"] != "ptfe", "ep_max_fraction_p"].min()
        for _, g in lighter.groupby(["layout.R2_ratio", "load.q0"])
    )
    narrows = bool((to_steel_p > to_steel_e).all())
    small = t[t["layout.R2_ratio"] == SMALLEST]
    out.append(
        f"**The PTFE intruders' localisation {'survives' if least else 'does not always survive'}** "
        f"where the elastic map has it: from "
        f"R2/R1 = {ptfe['layout.R2_ratio'].min():.2f} up, PTFE intruders "
        f"{'pass less than steel and aluminium ones at every radius and load' if least else 'do not always pass the least'}, "
        f"{span(ptfe['ep_max_fraction_p'])} of the shock (elastic: {span(ptfe['ep_max_fraction_e'])}). "
        f"The heavy intruders' plastic work {'narrows' if narrows else 'does not always narrow'} the gap: "
        f"at {loads[-1] * 1e-3:g} kN/m PTFE intruders pass {span(to_steel_p, ratio)} times the share of "
        f"steel ones of the same radius (elastic: {span(to_steel_e, ratio)}). At R2/R1 = {SMALLEST:.2f} "
        f"there is none to keep: {span(small['ep_max_fraction_p'])} whatever the material and load "
        f"(elastic: {span(small['ep_max_fraction_e'])})."
    )
    moves = []
    for metric, label, fmt in (("ep_max_fraction", "least peak share", pct), ("max_von_mises", "least stress", mpa)):
        for q in loads:
            e, p = best(t, metric, "_e", q), best(t, metric, "_p", q)
            where = design_name(e) if design_name(e) == design_name(p) else f"{design_name(e)} -> {design_name(p)}"
            moves.append(f"{label} at {q * 1e-3:g} kN/m: {where}, {fmt(e[metric + '_e'])} -> {fmt(p[metric + '_p'])}")
    kept = all(
        design_name(best(t, m, "_e", q)) == design_name(best(t, m, "_p", q))
        for m in ("ep_max_fraction", "max_von_mises")
        for q in loads
    )
    out.append(
        f"**The best design {'does not move' if kept else 'moves'}** (per load, elastic -> "
        f"yielding): " + "; ".join(moves) + "."
    )
    return [f"- {f}" for f in out]


def comparison(t: pd.DataFrame | None = None, law: str = "thornton") -> str:
    """The Markdown that docs/studies.md shows for the twin of normal law `law`: the share
    table and the findings."""
    t = read_tables(ELASTIC, TWINS[law]) if t is None else t
    return "\n".join(share_table(t) + [""] + facts(t, law))


if __name__ == "__main__":
    law = sys.argv[1] if len(sys.argv) > 1 else "thornton"
    if law not in TWINS:
        sys.exit(f"compare-intruder-maps.py: the law {law!r} has no twin table; allowed: {', '.join(TWINS)}")
    sys.stdout.write(comparison(law=law) + "\n")

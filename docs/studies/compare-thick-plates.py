"""The paper's protector on plates of real thickness, computed from the two committed
tables (docs/studies/thick-plates/results.csv: loaded in the plate's plane, as in the
paper; docs/studies/thick-plates-face/results.csv: pressed on the plate's face, which
bends): the part of docs/studies.md "Plates of real thickness" between its markers,
printed as the Markdown that page shows.

    python docs/studies/compare-thick-plates.py

Nothing is run: the numbers are the tables'. Fractions are of the shock's work e_in
(docs/output.md), shown in percent; stresses in MPa: the largest von Mises stress
averaged over a ball about a point of the plate's surface (`max_von_mises_ball`, of radius
`plate.stress_radius`: 2.5 mm in plane, the 2D disc's; 5 mm on the face, the contacts'
disc), which converges under mesh refinement where the largest stress at a quadrature
point does not.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pandas as pd

HERE = Path(__file__).resolve().parent
IN_PLANE = HERE / "thick-plates" / "results.csv"
FACE = HERE / "thick-plates-face" / "results.csv"
#: Each table's thickness column (the slab's z extent in plane, the plate's x extent on its face).
THICKNESS = {"in_plane": "plate.size[2]", "face": "plate.size[0]"}
MATERIAL = "layout.intruder_material"
#: The stress the page quotes (see the module docstring).
STRESS = "max_von_mises_ball"
#: The loadings, as the page names them.
LOADINGS = {"in_plane": "in plane", "face": "on the face"}


def read_table(path: Path, loading: str) -> pd.DataFrame:
    """One table, its thickness column renamed `h` [m]; every design must have completed."""
    t = pd.read_csv(path)
    bad = t[t["status"] != "ok"]
    if len(bad):
        raise ValueError(f"{path}: designs {list(bad['design'])} did not complete")
    if set(t[MATERIAL]) != {"steel", "ptfe"}:
        raise ValueError(f"{path}: the intruders must be steel and ptfe, not {sorted(set(t[MATERIAL]))}")
    return t.rename(columns={THICKNESS[loading]: "h"})


def read_tables(in_plane: Path = IN_PLANE, face: Path = FACE) -> dict[str, pd.DataFrame]:
    """Both tables, by loading; each holds every thickness with both intruder materials."""
    tables = {"in_plane": read_table(in_plane, "in_plane"), "face": read_table(face, "face")}
    for name, t in tables.items():
        per = t.groupby("h")[MATERIAL].apply(sorted)
        if not all(v == ["ptfe", "steel"] for v in per):
            raise ValueError(f"{name}: each thickness needs one steel and one ptfe design")
    return tables


def pct(x: float) -> str:
    """A fraction in percent, three significant digits."""
    return f"{100.0 * x:.3g}%"


def mpa(x: float) -> str:
    """A stress [Pa] in MPa, three significant digits."""
    return f"{x * 1e-6:.3g} MPa"


def mm(x: float) -> str:
    """A length [m] in mm."""
    return f"{x * 1e3:g} mm"


def pair(t: pd.DataFrame, metric: str) -> pd.DataFrame:
    """(thickness -> steel, ptfe) of one metric."""
    return t.pivot(index="h", columns=MATERIAL, values=metric).sort_index()


def share_table(tables: dict[str, pd.DataFrame]) -> list[str]:
    """Per thickness and loading: the plate's peak share and largest stress with steel and
    with PTFE intruders, and PTFE's share over steel's."""
    head = ["h"] + [
        f"{LOADINGS[k]}: {what}"
        for k in tables
        for what in ("peak share steel / PTFE", "PTFE / steel", "ball-averaged stress steel / PTFE")
    ]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    shares = {k: pair(t, "ep_max_fraction") for k, t in tables.items()}
    stresses = {k: pair(t, STRESS) for k, t in tables.items()}
    for h in shares["in_plane"].index:
        cells = [mm(h)]
        for k in tables:
            s, v = shares[k].loc[h], stresses[k].loc[h]
            cells += [
                f"{pct(s['steel'])} / {pct(s['ptfe'])}",
                f"{s['ptfe'] / s['steel']:.3f}",
                f"{mpa(v['steel'])} / {mpa(v['ptfe'])}",
            ]
        lines.append("| " + " | ".join(cells) + " |")
    return lines


def findings(tables: dict[str, pd.DataFrame]) -> list[str]:
    """The page's bullets, each computed from the tables."""
    out = []
    sh = {k: pair(t, "ep_max_fraction") for k, t in tables.items()}
    vm = {k: pair(t, STRESS) for k, t in tables.items()}
    thin, thick = sh["in_plane"].index[0], sh["in_plane"].index[-1]
    p = sh["in_plane"]
    ratio = p["ptfe"] / p["steel"]
    out.append(
        f"- **In plane, the thicker slab takes less, and PTFE's localisation grows.** From "
        f"{mm(thin)} to {mm(thick)} the plate's peak share falls from {pct(p.loc[thin, 'steel'])} to "
        f"{pct(p.loc[thick, 'steel'])} with steel intruders and from {pct(p.loc[thin, 'ptfe'])} to "
        f"{pct(p.loc[thick, 'ptfe'])} with PTFE ones; its ball-averaged stress from "
        f"{mpa(vm['in_plane'].loc[thin, 'steel'])} to {mpa(vm['in_plane'].loc[thick, 'steel'])} (steel) and "
        f"{mpa(vm['in_plane'].loc[thin, 'ptfe'])} to {mpa(vm['in_plane'].loc[thick, 'ptfe'])} (PTFE). "
        f"PTFE intruders pass {ratio.loc[thin]:.3f} of steel's share at {mm(thin)} and "
        f"{ratio.min():.3f} to {ratio.max():.3f} over the range, "
        + ("less at every thickness" if (p["ptfe"] < p["steel"]).all() else "not less at every thickness")
        + (", the ratio falling as the slab thickens" if ratio.is_monotonic_decreasing else "")
        + "."
    )
    f = sh["face"]
    fr = f["ptfe"] / f["steel"]
    close = fr[fr > 0.5]
    far = fr[fr <= 0.5]
    out.append(
        "- **On the face, a thin plate bends and takes the shock whatever the intruders.** At "
        + (", ".join(mm(h) for h in close.index) or "no thickness")
        + f" PTFE intruders pass {', '.join(f'{r:.2f}' for r in close)} of steel's share "
        + f"({', '.join(pct(f.loc[h, 'ptfe']) + ' against ' + pct(f.loc[h, 'steel']) for h in close.index)}): "
        "the compliant plate lets the whole packing push into it, and the intruders hold back little. "
        + (
            f"From {mm(far.index[0])} the localisation returns: PTFE passes "
            f"{', '.join(f'{r:.3g}' for r in far)} of steel's share at "
            f"{', '.join(mm(h) for h in far.index)} ({pct(f.loc[far.index[-1], 'ptfe'])} against "
            f"{pct(f.loc[far.index[-1], 'steel'])} at {mm(far.index[-1])})."
            if len(far)
            else ""
        )
    )
    both = sh["face"] / sh["in_plane"]
    more = [h for h in both.index if (both.loc[h] > 1.0).any()]
    out.append(
        f"- **Face against plane.** At equal thickness the face-loaded plate takes "
        f"{both['steel'].min():.2f} to {both['steel'].max():.2f} times the in-plane share with steel "
        f"intruders and {both['ptfe'].min():.3g} to {both['ptfe'].max():.3g} times with PTFE ones; "
        f"more than in plane only at {', '.join(mm(h) for h in more) or 'no thickness'}, where the plate "
        f"bends; at {mm(thick)} {both.loc[thick, 'steel']:.2f} (steel) and {both.loc[thick, 'ptfe']:.3g} (PTFE) "
        f"times: the 100 x 100 mm plate has ten times the mass of the 10 x 100 mm slab loaded in "
        f"plane, and its bending stiffness grows as the cube of its thickness."
    )
    best = {k: sh[k].stack().idxmin() for k in sh}
    out.append(
        "- **The best protector of each table** (least peak share): "
        + "; ".join(
            f"{LOADINGS[k]}: {b[1]} intruders on the {mm(b[0])} plate, {pct(sh[k].loc[b])}" for k, b in best.items()
        )
        + ". PTFE intruders are the better choice at every thickness of both tables"
        + ("" if all((sh[k]["ptfe"] <= sh[k]["steel"]).all() for k in sh) else " but one")
        + "."
    )
    return out


def comparison(in_plane: Path = IN_PLANE, face: Path = FACE) -> str:
    """The page's part between its markers: the table and the findings."""
    tables = read_tables(in_plane, face)
    return "\n".join(share_table(tables) + [""] + findings(tables))


if __name__ == "__main__":
    sys.stdout.write(comparison() + "\n")

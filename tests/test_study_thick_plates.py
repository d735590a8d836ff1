"""The worked study of plates of real thickness (docs/studies/thick-plates*.toml) as
committed: each table is of its study file and complete, the comparison on
docs/studies.md is the script's output from the two tables, and the written conclusions
quote only what the script computes. Nothing is run: the tables are read."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

import pandas as pd
import pytest

from granplate.study.spec import load_study

from conftest import script_module

STUDIES = Path(__file__).resolve().parent.parent / "docs" / "studies"
NAMES = ("thick-plates", "thick-plates-face")
BEGIN, END = "<!-- compare-thick-plates.py: begin -->\n", "\n<!-- compare-thick-plates.py: end -->"


def compare_module():
    """docs/studies/compare-thick-plates.py, imported from its file."""
    return script_module(STUDIES / "compare-thick-plates.py", "compare_thick_plates")


@pytest.mark.parametrize("name", NAMES)
def test_committed_table_is_of_its_study_file(name):
    """Each committed table holds exactly its study file's designs (intruder material x the
    thickness with its elements through it), all completed, their energy balance held, and
    the folder's study.toml (the report's definition) is that file."""
    study = load_study(STUDIES / f"{name}.toml")
    rows = pd.read_csv(STUDIES / name / "results.csv")
    assert len(rows) == len(study.designs) == 10
    for (_, row), design in zip(rows.iterrows(), study.designs):
        assert tuple(row[n] for n in study.names) == design
        assert row["status"] == "ok" and abs(row["energy_residual_max"]) < 1e-4
    assert (STUDIES / name / "study.toml").read_text() == (STUDIES / f"{name}.toml").read_text()
    assert (STUDIES / name / "report.html").is_file()


def test_the_in_plane_study_at_1_mm_is_the_3d_twin():
    """The in-plane study's 1 mm designs are the 3D twins of ptfe-r05 and steel-r05 (the
    steel packings' step, 0.2 us, for both), changed only in the stress's averaging radius,
    which no run reads: the same resolved scenarios."""
    import dataclasses

    import granplate as gp
    from granplate.setup.geometry import resolve

    study = load_study(STUDIES / "thick-plates.toml")
    for i, (material, h, _) in enumerate(study.designs):
        if h != 0.001:
            continue
        twin = gp.with_changes(
            gp.preset("3d-steel-r05" if material == "steel" else "3d-ptfe-r05"),
            {"time.dt_max": 2e-7, "time.dt_initial": 2e-7, "plate.stress_radius": 0.0025},
        )
        a, b = resolve(study.scenario(i)), resolve(twin)
        assert dataclasses.replace(a, name="", description="") == dataclasses.replace(b, name="", description="")


def test_page_shows_the_comparison_of_the_committed_tables():
    """The part of docs/studies.md between its markers is the script's output from the
    committed tables, as printed (no hand-copied number)."""
    page = (STUDIES.parent / "studies.md").read_text()
    assert BEGIN in page and END in page
    assert page.split(BEGIN, 1)[1].split(END, 1)[0] == compare_module().comparison()


#: A figure the conclusions quote: a percentage or a stress in MPa, or a ratio 0.xxx.
FIGURE = r"(?<![\d.])(?:\d+(?:\.\d+)?%|\d+(?:\.\d+)? MPa|0\.\d+(?![\d%]))"


@pytest.mark.parametrize("name", NAMES)
def test_conclusion_quotes_only_the_comparison(name):
    """Every figure of a study's written conclusion (its report page) is one that the
    comparison computes from the tables."""
    conclusion = " ".join(tomllib.loads((STUDIES / f"{name}.toml").read_text())["report"]["conclusion"].split())
    quoted = set(re.findall(FIGURE, conclusion))
    assert len(quoted) >= 6
    computed = set(re.findall(FIGURE, " ".join(compare_module().comparison().split())))
    assert quoted <= computed, quoted - computed


def test_comparison_refuses_incomplete_tables(tmp_path):
    """A table with a failed design, or a thickness without both intruder materials, is
    refused, not compared."""
    m = compare_module()
    rows = (STUDIES / "thick-plates" / "results.csv").read_text().splitlines()
    failed = rows[:2] + [rows[2].replace(",ok,", ",RuntimeError: boom,")] + rows[3:]
    (tmp_path / "failed.csv").write_text("\n".join(failed) + "\n")
    with pytest.raises(ValueError, match="did not complete"):
        m.read_tables(tmp_path / "failed.csv", STUDIES / "thick-plates-face" / "results.csv")
    (tmp_path / "short.csv").write_text("\n".join(rows[:-1]) + "\n")
    with pytest.raises(ValueError, match="one steel and one ptfe"):
        m.read_tables(tmp_path / "short.csv", STUDIES / "thick-plates-face" / "results.csv")


def test_protector_3d_conclusion_is_its_trials_table():
    """The 3D optimisation's written conclusion (docs/studies/protector-3d.toml) quotes its
    committed trials.csv: the best feasible design and its figures, the best feasible of
    each middle layer, the mass range of the designs with two loaded cells, the counts."""
    t = pd.read_csv(STUDIES / "protector-3d" / "trials.csv")
    conclusion = " ".join(tomllib.loads((STUDIES / "protector-3d.toml").read_text())["report"]["conclusion"].split())
    done = t[t["state"] == "COMPLETE"]
    feasible = done[done["feasible"] == "yes"]
    assert f"{len(t)} trials, {len(feasible)} feasible" in conclusion
    best = feasible.loc[feasible["ep_max_fraction"].idxmin()]
    assert (
        best["layout.layers[0].count"],
        best["layout.layers[1].material"],
        best["layout.layers[2].count"],
        best["layout.layers[2].material"],
    ) == (1, "ptfe", 2, "aluminium")
    assert f"PTFE spheres of {1e3 * best['layout.layers[1].radius']:.2f} mm" in conclusion
    assert f"({best['granular_mass']:.3f} kg): {100 * best['ep_max_fraction']:.4f}%" in conclusion
    assert f"largest stress is {best['max_von_mises'] / 1e3:.0f} kPa" in conclusion
    dominated = feasible[
        (feasible["ep_max_fraction"] >= best["ep_max_fraction"]) & (feasible["max_von_mises"] >= best["max_von_mises"])
    ]
    assert len(dominated) == len(feasible)  # the front within the window is that one design

    def best_of(rows):
        return rows.loc[rows["ep_max_fraction"].idxmin()]

    steel_back = best_of(
        feasible[(feasible["layout.layers[1].material"] == "ptfe") & (feasible["layout.layers[2].material"] == "steel")]
    )
    assert f"{100 * steel_back['ep_max_fraction']:.4f}% ({steel_back['granular_mass']:.3f} kg)" in conclusion
    alu = best_of(feasible[feasible["layout.layers[1].material"] == "aluminium"])
    assert f"{100 * alu['ep_max_fraction']:.3f}% ({alu['granular_mass']:.3f} kg)" in conclusion
    steel = feasible[feasible["layout.layers[1].material"] == "steel"].sort_values("layout.layers[1].radius")
    for _, row in steel.iloc[[0, -1]].iterrows():
        assert f"{100 * row['ep_max_fraction']:.3g}% at {1e3 * row['layout.layers[1].radius']:.2f} mm" in conclusion
    two = done[done["layout.layers[0].count"] == 2]
    assert (two["feasible"] == "no").all()
    assert f"({two['granular_mass'].min():.2f} to {two['granular_mass'].max():.2f} kg)" in conclusion
    assert f"{100 * two['ep_max_fraction'].min():.5f}% at {best_of(two)['granular_mass']:.3f} kg" in conclusion

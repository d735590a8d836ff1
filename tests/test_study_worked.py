"""The worked intruder maps in docs/studies (elastic contacts and contacts that yield) as
committed: each table is of its study file, the twin differs from the elastic map in the
normal law alone, the designs that never reach the yield onset are Hertz's in both, and
the comparison and conclusion on the pages are what the committed tables give. Nothing is
run: the tables are read."""

from __future__ import annotations

import csv
import re
import tomllib
from pathlib import Path

import pytest

from granplate.study.spec import load_study

from conftest import script_module

STUDIES = Path(__file__).resolve().parent.parent / "docs" / "studies"
ELASTIC, PLASTIC, JOHNSON = "intruder-map", "intruder-map-plastic", "intruder-map-johnson"
BEGIN, END = "<!-- compare-intruder-maps.py: begin -->\n", "\n<!-- compare-intruder-maps.py: end -->"
#: the page's block of each twin's comparison (normal law -> its markers)
BLOCKS = {
    "thornton": (BEGIN, END),
    "johnson": (
        "<!-- compare-intruder-maps.py johnson: begin -->\n",
        "\n<!-- compare-intruder-maps.py johnson: end -->",
    ),
}


def compare_module():
    """docs/studies/compare-intruder-maps.py, imported from its file."""
    return script_module(STUDIES / "compare-intruder-maps.py", "compare_intruder_maps")


def table(name: str) -> list[dict[str, str]]:
    with open(STUDIES / name / "results.csv", newline="") as f:
        return list(csv.DictReader(f))


def value(text: str):
    """A CSV cell as the study's value: a number where it is one, else the string."""
    try:
        return float(text)
    except ValueError:
        return text


@pytest.mark.parametrize("name", [ELASTIC, PLASTIC, JOHNSON])
def test_committed_table_is_of_its_study_file(name):
    """Each committed table holds exactly its study file's designs, in order, all completed,
    and the folder's study.toml (the report's definition) is that file."""
    study = load_study(STUDIES / f"{name}.toml")
    rows = table(name)
    assert len(rows) == len(study.designs) == 36
    for row, design in zip(rows, study.designs):
        assert tuple(value(row[n]) for n in study.names) == design
        assert row["status"] == "ok"
    assert (STUDIES / name / "study.toml").read_text() == (STUDIES / f"{name}.toml").read_text()
    assert (STUDIES / name / "report.html").is_file()


@pytest.mark.parametrize("name, law", [(PLASTIC, "thornton"), (JOHNSON, "johnson")])
def test_twin_differs_from_the_elastic_map_in_the_normal_law_alone(name, law):
    """Each twin is the elastic map with its contact.normal_law and the yield strength that
    law needs for aluminium: same base, parameters, objectives, designs."""
    elastic, plastic = load_study(STUDIES / f"{ELASTIC}.toml"), load_study(STUDIES / f"{name}.toml")
    assert (plastic.base_name, plastic.names, plastic.designs) == (elastic.base_name, elastic.names, elastic.designs)
    added = {k: v for k, v in plastic.fixed.items() if k not in elastic.fixed}
    assert added == {"contact.normal_law": law, "materials.aluminium.Y": 2.76e8}
    assert all(plastic.fixed[k] == v for k, v in elastic.fixed.items())
    assert plastic.extra["objectives"] == elastic.extra["objectives"]
    assert elastic.base.contact.normal_law == "hertz" and plastic.base.contact.normal_law == law
    # the built-in yield strengths the header states: S355 steel, unfilled PTFE
    assert (plastic.base.material("steel").Y, plastic.base.material("ptfe").Y) == (355e6, 11e6)


@pytest.mark.parametrize("name, rtol", [(PLASTIC, 0.0), (JOHNSON, 1e-9)])
def test_contacts_below_the_yield_onset_are_hertz_in_both_tables(name, rtol):
    """Both yielding laws are Hertz's below p_y = 1.6 Y (docs/model.md P1-P2, J1): a design
    whose contacts never reach the onset in the elastic map is the same in the twin (to the
    last digit under Thornton's law, to round-off under "johnson", which writes Hertz's force
    in its own units), with no plastic work; in the twin, plastic work appears exactly where
    the onset ratio passes 1, and it is part of the dissipated share."""
    elastic, plastic = table(ELASTIC), table(name)
    below = [i for i, r in enumerate(elastic) if float(r["yield_onset_ratio"]) <= 1.0]
    assert below  # the map has such designs (PTFE intruders at the weakest shock)
    for i in below:
        for metric in (
            "ep_max_fraction",
            "eg_max_fraction",
            "dissipated_fraction",
            "max_von_mises",
            "max_contact_pressure",
            "n_steps",
        ):
            assert float(elastic[i][metric]) == pytest.approx(float(plastic[i][metric]), rel=rtol, abs=0), (i, metric)
    for e, p in zip(elastic, plastic):
        assert float(e["plastic_fraction"]) == 0.0
        w = float(p["plastic_fraction"])
        assert (w > 0.0) == (float(p["yield_onset_ratio"]) > 1.0), p["design"]
        assert 0.0 <= w <= float(p["dissipated_fraction"]) <= 1.0


@pytest.mark.parametrize("law", sorted(BLOCKS))
def test_page_shows_the_comparison_of_the_committed_tables(law):
    """Each comparison in docs/studies.md is the script's output from the committed tables,
    as printed (no hand-copied number)."""
    page = (STUDIES.parent / "studies.md").read_text()
    begin, end = BLOCKS[law]
    assert begin in page and end in page
    shown = page.split(begin, 1)[1].split(end, 1)[0]
    assert shown == compare_module().comparison(law=law)


#: A figure the pages quote: a percentage, a stress in MPa or a ratio, alone or as "a to b".
FIGURE = r"(?<![\d.])(?:\d+\.\d%|\d+\.\d MPa|\d\.\d\d(?![\d%]))"
SPAN = rf"(?:{FIGURE}) to (?:{FIGURE})"


def figures_in(text: str) -> tuple[set[str], set[str]]:
    """(the spans "a to b", the figures outside them) that a text quotes."""
    text = " ".join(text.split())
    spans = set(re.findall(SPAN, text))
    return spans, set(re.findall(FIGURE, re.sub(SPAN, " ", text)))


@pytest.mark.parametrize("name, law", [(PLASTIC, "thornton"), (JOHNSON, "johnson")])
def test_twin_conclusion_quotes_only_the_comparison(name, law):
    """Every figure of each twin's written conclusion (its report page), and every span
    "a to b" as a whole, is one that the comparison computes from the tables."""
    conclusion = tomllib.loads((STUDIES / f"{name}.toml").read_text())["report"]["conclusion"]
    spans, singles = figures_in(conclusion)
    assert len(spans) >= 8 and len(singles) >= 4
    computed = " ".join(compare_module().comparison(law=law).split())
    computed_spans = figures_in(computed)[0]
    every = set(re.findall(FIGURE, computed))
    assert spans <= computed_spans, spans - computed_spans
    assert singles <= every, singles - every
    counts = re.search(r"presses (\d+) of its (\d+) designs", " ".join(conclusion.split())).groups()
    assert f"{counts[0]} of its {counts[1]} designs" in computed


def test_comparison_refuses_tables_of_other_designs(tmp_path):
    """Tables that do not hold the same completed designs are refused, not compared."""
    m = compare_module()
    rows = (STUDIES / ELASTIC / "results.csv").read_text().splitlines()
    (tmp_path / "short.csv").write_text("\n".join(rows[:-1]) + "\n")
    with pytest.raises(ValueError, match="same designs"):
        m.read_tables(STUDIES / ELASTIC / "results.csv", tmp_path / "short.csv")
    failed = rows[:2] + [rows[2].replace(",ok,", ",RuntimeError: boom,")] + rows[3:]
    (tmp_path / "failed.csv").write_text("\n".join(failed) + "\n")
    with pytest.raises(ValueError, match="did not complete"):
        m.read_tables(tmp_path / "failed.csv", STUDIES / PLASTIC / "results.csv")


@pytest.mark.parametrize(
    "name", [ELASTIC, PLASTIC, "calibration", "two-layer", "thick-plates", "thick-plates-face", "protector-3d"]
)
def test_committed_page_is_that_of_its_committed_table(name):
    """Each worked study's committed report.html is the interactive page the code writes
    from the committed table and figures, and its report_assets/ are the package's own
    (plotly.js and the page's script and style): nothing stale is committed."""
    from granplate.study import explorer as X
    from granplate.study.outcome import read_outcome
    from granplate.study.report import kept_figures, paper_figures

    folder = STUDIES / name
    out = read_outcome(folder)
    page = X.explorer_html(out, X.explorer_data(out, kept_figures(out)), X.explorer_figures(out), paper_figures(out))
    assert (folder / "report.html").read_text() == page
    assets = folder / X.ASSETS
    assert (assets / X.PLOTLY_JS).read_bytes() == X.plotly_source().read_bytes()
    for asset in X.OWN_ASSETS:
        assert (assets / asset).read_bytes() == (Path(X.__file__).parent / "assets" / asset).read_bytes()

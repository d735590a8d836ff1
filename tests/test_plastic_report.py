"""The report's section "Contacts that yield": the plastic twins are the presets with
the Thornton law (or the law "johnson") and nothing else changed, the section's numbers are each result's own
`summary`, its verdicts the statement checks judged on the twins, the run table's p0
columns the Dataset's per-pair pressures, and plastic work appears exactly where a
contact passed the yield onset."""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import pytest

import granplate as gp
from granplate.errors import YieldWarning
from granplate.paper import plastic as pl
from granplate.paper import plots, report
from granplate.paper.statements import statements
from granplate.results.dataset import pair_table, summary
from granplate.setup.presets import preset, preset_names

from short_results import T_END, short_results
from conftest import section_titles


@pytest.fixture(scope="module")
def elastic():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", YieldWarning)
        return short_results()


@pytest.fixture(scope="module")
def twins():
    return {n: gp.simulate(pl.twin_scenario(n), t_end=T_END, progress=False) for n in pl.twin_presets()}


@pytest.fixture(scope="module")
def measured():
    return {n: gp.simulate(pl.twin_scenario(n, law="johnson"), t_end=T_END, progress=False) for n in pl.twin_presets()}


def _col(header, name):
    return list(header).index(name)


@pytest.mark.parametrize("law", ["thornton", "johnson"])
def test_twins_are_the_presets_with_their_law_only(law):
    """A twin differs from its preset in contact.normal_law alone; the bare plate has no twin;
    an unknown law has no twins."""
    assert pl.twin_presets() == [n for n in preset_names() if n != "bare-plate"]
    for n in pl.twin_presets():
        s, t = preset(n), pl.twin_scenario(n, law=law)
        assert t.contact.normal_law == law and s.contact.normal_law == "hertz"
        assert replace(t, contact=replace(t.contact, normal_law="hertz"), description=s.description) == s
    assert pl.twin_preset(pl.twin_name("steel-r1", law)) == "steel-r1" and pl.twin_preset("steel-r1") is None
    assert pl.twin_name("steel-r1", law) == f"{pl.TWIN_LAWS[law]}/steel-r1"
    with pytest.raises(ValueError, match="hertz"):
        pl.twin_scenario("steel-r1", law="hertz")


@pytest.mark.parametrize("law", ["thornton", "johnson"])
def test_plastic_work_exactly_where_contacts_pass_the_onset(twins, measured, elastic, law):
    """D_plastic > 0 in a twin iff one of its pairs' p0 passed 1.6 Y; elastic runs do no plastic
    work; a twin whose contacts stay below the onset is its elastic run (both laws are Hertz's
    below it)."""
    runs = twins if law == "thornton" else measured
    for n, ds in runs.items():
        worst = pl.worst_pair(ds)["yield_onset_ratio"]
        work = float(ds.D_plastic[-1])
        assert (work > 0) == (worst > 1.0), (n, worst, work)
        assert float(elastic[n].D_plastic[-1]) == 0.0
        if worst < 1.0:  # below the onset Thornton's law is Hertz's: the twin is the elastic run
            np.testing.assert_allclose(ds.E_plate.values, elastic[n].E_plate.values, rtol=1e-9, atol=0.0)
    # both sides of the onset are in these runs (steel and the strong shock yield; the weak one does not)
    assert any(pl.worst_pair(d)["yield_onset_ratio"] > 1 for d in runs.values())
    assert any(pl.worst_pair(d)["yield_onset_ratio"] < 1 for d in runs.values())


def test_case_table_is_each_results_summary(elastic, twins):
    """Each cell is elastic / yielding from gp.summary of the two Datasets; the bare plate
    stands in both columns; changing a twin changes its cells."""
    rows = {r[0].split(" ")[0]: r for r in pl.case_table(elastic, twins)}
    assert list(rows) == preset_names()
    assert rows["bare-plate"][0] == "bare-plate (its own twin)"
    h = pl.CASE_HEADER
    for n in pl.twin_presets():
        e, y = summary(elastic[n]), summary(twins[n])
        r = rows[n]
        assert r[_col(h, "plate peak")] == f"{100 * e['ep_max_fraction']:.1f}% / {100 * y['ep_max_fraction']:.1f}%"
        assert r[_col(h, "max von Mises [MPa]")] == f"{e['max_von_mises'] / 1e6:.1f} / {y['max_von_mises'] / 1e6:.1f}"
        assert r[_col(h, "D_plastic / E_shock")] == f"{100 * y['plastic_fraction']:.1f}%"
        ratio = max(p["yield_onset_ratio"] for p in y["contact_pairs"])
        assert r[_col(h, "largest p0 / (1.6 Y)")].split(" / ")[1].startswith(f"{ratio:.2f} (")
    changed = dict(twins)
    changed["steel-r1"] = twins["steel-r1"].copy(deep=True)
    changed["steel-r1"]["D_plastic"] = changed["steel-r1"]["D_plastic"] * 0.5
    new = {r[0]: r for r in pl.case_table(elastic, changed)}["steel-r1"]
    half = summary(twins["steel-r1"])["plastic_fraction"] / 2
    assert new[_col(h, "D_plastic / E_shock")] == f"{100 * half:.1f}%"


def test_case_table_has_a_third_column_of_the_measured_law(elastic, twins, measured):
    """With the twins of the law "johnson", each cell is elastic / thornton / johnson, the third
    from gp.summary of its own Dataset; the bare plate stands in every column."""
    rows = {r[0].split(" ")[0]: r for r in pl.case_table(elastic, twins, measured)}
    h = pl.CASE_HEADER
    assert rows["bare-plate"][_col(h, "plate peak")].count(" / ") == 2
    for n in pl.twin_presets():
        e, y, m = summary(elastic[n]), summary(twins[n]), summary(measured[n])
        cells = [f"{100 * x['ep_max_fraction']:.1f}%" for x in (e, y, m)]
        assert rows[n][_col(h, "plate peak")] == " / ".join(cells)
        assert rows[n][_col(h, "D_plastic / E_shock")] == " / ".join(
            f"{100 * x['plastic_fraction']:.1f}%" for x in (y, m)
        )


def test_statements_are_judged_on_the_twins(elastic, twins):
    """The yielding column is `statements` of the twins (the bare plate as itself), row by row."""
    pairs = pl.statement_pairs(elastic, twins)
    assert [e.quantity for e, _ in pairs] == [r.quantity for r in statements(elastic)]
    on_twins = statements({**{"bare-plate": elastic["bare-plate"]}, **twins})
    by_key = {r.key: r for r in on_twins}
    for e, y in pairs:
        assert (y.ours_text, y.holds) == (by_key[y.key].ours_text, by_key[y.key].holds)
    table = pl.statement_table(pairs)
    assert [r[-1] for r in table] == [pl.movement(e.holds, y.holds) for e, y in pairs]


def test_movement_words():
    """Each pair of verdicts has its word; an unjudged one has none."""
    assert pl.movement(True, True) == "still holds"
    assert pl.movement(False, False) == "still does not hold"
    assert pl.movement(True, False) == "no longer holds"
    assert pl.movement(False, True) == "now holds"
    assert pl.movement(None, True) == pl.movement(True, None) == "-"


def test_run_table_shows_each_runs_largest_p0(elastic):
    """The run table's p0 columns are the pair with the largest ratio, from the Dataset's
    pair_* variables; a run without contacts shows "-"."""
    rows = {r[0]: r for r in report.run_rows(elastic)}
    i_p, i_r = report.RUN_HEADER.index("largest p0 [MPa] (pair)"), report.RUN_HEADER.index("p0 / (1.6 Y)")
    assert rows["bare-plate"][i_p] == rows["bare-plate"][i_r] == "-"
    for n in pl.twin_presets():
        ds = elastic[n]
        k = int(np.nanargmax(ds.pair_yield_onset_ratio.values))
        assert rows[n][i_p] == f"{ds.pair_max_contact_pressure.values[k] / 1e6:.1f} ({ds.material_pair.values[k]})"
        assert rows[n][i_r] == f"{ds.pair_yield_onset_ratio.values[k]:.2f}"
    pairs = pl.pair_rows({"steel-r1": elastic["steel-r1"]})
    assert [r[1] for r in pairs] == [p["pair"] for p in pair_table(elastic["steel-r1"])]


def test_report_has_the_section_only_with_twins(elastic, twins, measured):
    """build_report adds "Contacts that yield" when given twins, and not without them; with the
    twins of the law "johnson" the conclusions and statements are judged three ways."""
    assert "Contacts that yield" not in section_titles(report.build_report(elastic, {}))
    blocks = report.build_report(elastic, {}, twins=twins)
    assert "Contacts that yield" in section_titles(blocks)
    tables = [b for b in blocks if b.kind == "table" and b.header == pl.CASE_HEADER]
    assert len(tables) == 1 and tables[0].rows == tuple(pl.case_table(elastic, twins))
    blocks = report.build_report(elastic, {}, twins=twins, measured=measured)
    assert "The paper's conclusions with the law that matches measurement" in section_titles(blocks)
    triples = [b for b in blocks if b.kind == "table" and b.header == pl.TRIPLE_HEADER]
    expected = pl.triple_table(pl.statement_triples(elastic, twins, measured))
    assert len(triples) == 1 and triples[0].rows == tuple(expected) and expected
    on_johnson = {r.key: r for r in statements({**{"bare-plate": elastic["bare-plate"]}, **measured})}
    for (_, _, m), row in zip(pl.statement_triples(elastic, twins, measured), expected):
        assert row[6] == on_johnson[m.key].ours_text


def test_yielding_figure_draws_every_run(elastic, twins, measured):
    """The figure's curves are the three runs' own E_plate and the twins' D_plastic [mJ]."""
    fig = plots.fig_yielding(elastic["ptfe-r05"], twins["ptfe-r05"], measured["ptfe-r05"])
    lines = {ln.get_gid(): ln for ax in fig.axes for ln in ax.get_lines()}
    np.testing.assert_array_equal(lines["plate:elastic"].get_ydata(), elastic["ptfe-r05"].E_plate.values * 1e3)
    np.testing.assert_array_equal(lines["plate:thornton"].get_ydata(), twins["ptfe-r05"].E_plate.values * 1e3)
    np.testing.assert_array_equal(lines["plate:johnson"].get_ydata(), measured["ptfe-r05"].E_plate.values * 1e3)
    np.testing.assert_array_equal(lines["plastic:thornton"].get_ydata(), twins["ptfe-r05"].D_plastic.values * 1e3)
    np.testing.assert_array_equal(lines["plastic:johnson"].get_ydata(), measured["ptfe-r05"].D_plastic.values * 1e3)
    assert all(ax.get_xlabel() == "time [ms]" and ax.get_ylabel() == "energy [mJ]" for ax in fig.axes)

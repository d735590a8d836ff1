"""The study report: built from a synthetic study folder whose metrics are known functions
of the parameters, its figures show exactly those values (one figure per varying metric,
units on every axis; the heat map of a 2-parameter grid cell by cell; the failures with
their messages); built at the end of a tiny real sweep by the CLI; the [report] targets
judge each combination of the choices by its own designs."""

from __future__ import annotations

import html
import re
from pathlib import Path

import numpy as np
import pytest

import granplate as gp
from granplate.cli import main
from granplate.errors import ScenarioError
from granplate.study import design as D
from granplate.study import plots as P
from granplate.study.outcome import read_outcome
from granplate.study.report import FIGURES, INPUTS_FILE, PAGE, best_designs, pareto_front, target_designs, write_report
from granplate.study.spec import parse_study
from granplate.study.sweep import write_table
from granplate.study.targets import judge, parse_report_table

STUDY_TOML = """base = "ptfe-r05"
[set]
"time.t_end" = 1e-6
[parameters]
"load.q0" = [1000.0, 2000.0, 4000.0]
"layout.R2_ratio" = [0.5, 1.0]
[objectives]
"ep_max_fraction" = "minimize"
"max_von_mises" = "minimize"
"""
#: The synthetic design that fails, and its message.
FAILED = 4
MESSAGE = "SimulationError: synthetic failure of design 4 at t = 1e-07 s"


def known_metrics(q0: float, r2: float) -> dict:
    """The synthetic metrics of a design: simple functions of its parameters."""
    return {
        "ep_max_fraction": q0 / 1e4 * r2,
        "max_von_mises": 1e3 * q0 / r2,
        "granular_mass": 0.1 + r2,
        "t_end": 1e-6,
        "n_steps": int(q0 / 100),
    }


def synthetic(folder: Path):
    """A sweep's folder written by hand: records with known metrics, one failure."""
    import tomllib

    study = parse_study(tomllib.loads(STUDY_TOML))
    keys = []
    for i, (q0, r2) in enumerate(study.designs):
        text = gp.dumps(study.scenario(i))
        key = D.design_key(text)
        keys.append(key)
        summary = {**known_metrics(q0, r2), "units": D.metric_units()}
        outcome = {
            "status": MESSAGE if i == FAILED else "ok",
            "summary": None if i == FAILED else summary,
            "elapsed_s": 0.0,
        }
        D.write_record(folder, D.make_record(key, study.changes(i), text, outcome))
    write_table(study, folder, keys)
    (folder / "study.toml").write_text(STUDY_TOML)
    return study


@pytest.fixture(scope="module")
def synthetic_report(tmp_path_factory):
    folder = tmp_path_factory.mktemp("synthetic")
    study = synthetic(folder)
    page = write_report(folder)
    return folder, study, page.read_text()


def test_outcome_reads_back_the_parameters_metrics_and_failures(synthetic_report):
    folder, study, _ = synthetic_report
    out = read_outcome(folder)
    assert out.kind == "sweep" and out.names == ("load.q0", "layout.R2_ratio")
    assert [r.ok for r in out.rows] == [i != FAILED for i in range(6)]
    for r, (q0, r2) in zip(out.rows, study.designs):
        assert r.params == {"load.q0": q0, "layout.R2_ratio": r2}
        if r.ok:
            assert r.metrics["ep_max_fraction"] == q0 / 1e4 * r2
    assert out.rows[FAILED].status == MESSAGE
    assert out.unit("max_von_mises") == "Pa" and out.unit("load.q0") == "N/m"


def test_one_figure_per_varying_metric_with_its_unit(synthetic_report):
    folder, _, page = synthetic_report
    out = read_outcome(folder)
    shown = {"ep_max_fraction": "-", "max_von_mises": "MPa", "granular_mass": "kg", "n_steps": "-"}
    for metric, unit in shown.items():
        assert (folder / FIGURES / f"metric-{metric}.png").read_bytes()[:4] == b"\x89PNG"
        fig = P.fig_metric(out, metric)
        assert [ax.get_ylabel() for ax in fig.axes] == [f"{metric} [{unit}]"] * 2
        assert [ax.get_xlabel() for ax in fig.axes] == ["load.q0 [N/m]", "layout.R2_ratio [-]"]
        # the points drawn are the metric's values (Pa in MPa), failed design left out
        drawn = np.concatenate([ln.get_ydata() for ln in fig.axes[0].get_lines()])
        expected = [
            known_metrics(q0, r2)[metric] * (1e-6 if unit == "MPa" else 1)
            for i, (q0, r2) in enumerate(zip(out.values("load.q0"), out.values("layout.R2_ratio")))
            if i != FAILED
        ]
        np.testing.assert_allclose(np.sort(drawn[np.isfinite(drawn)]), np.sort(expected), rtol=1e-12)
    # constant metrics are named, not drawn
    assert not (folder / FIGURES / "metric-t_end.png").exists()
    markdown = (folder / "report.md").read_text()
    assert "`t_end`" in markdown.split("Not drawn", 1)[1].split("\n", 1)[0]


def test_heat_map_of_a_two_parameter_grid_shows_each_design_in_its_cell(synthetic_report):
    folder, _, page = synthetic_report
    out = read_outcome(folder)
    assert P.heat_axes(out) == ("load.q0", "layout.R2_ratio", [])
    fig = P.fig_heatmap(out, "ep_max_fraction")
    z = np.ma.filled(fig.axes[0].images[0].get_array().astype(float), np.nan)
    expected = np.array([[q0 / 1e4 * r2 for q0 in (1e3, 2e3, 4e3)] for r2 in (0.5, 1.0)])
    expected[0, 2] = np.nan  # design 4 = (q0 4000, R2 0.5) failed
    np.testing.assert_array_equal(z, expected)
    assert fig.axes[-1].get_ylabel() == "ep_max_fraction [-]"  # the colour bar
    for m in ("ep_max_fraction", "max_von_mises"):
        assert (folder / FIGURES / f"heatmap-{m}.png").is_file()
    assert "Heat maps" in page


def test_heat_maps_of_three_parameters_are_one_panel_per_value_of_the_third(tmp_path):
    synthetic(tmp_path)
    out = read_outcome(tmp_path)
    for r in out.rows:  # a third parameter, crossing the grid: two copies of each design
        r.params["contact.mu"] = 0.1
    rows = list(out.rows)
    out.rows = rows + [type(r)(r.number + 6, {**r.params, "contact.mu": 0.2}, r.metrics, r.status, r.key) for r in rows]
    out.names = out.names + ("contact.mu",)
    fig = P.fig_heatmap(out, "max_von_mises")
    panels = [ax for ax in fig.axes if ax.images]
    assert [ax.get_title() for ax in panels] == ["contact.mu = 0.1", "contact.mu = 0.2"]
    # a parameter zipped with another is no axis of its own: named with it
    for r in out.rows:
        r.params["contact.alpha_n"] = r.params["contact.mu"] / 10
    out.names = out.names + ("contact.alpha_n",)
    assert P.varied(out) == ["load.q0", "layout.R2_ratio", "contact.mu"] and P.is_grid(out)
    fig = P.fig_heatmap(out, "max_von_mises")
    assert [ax.get_title() for ax in fig.axes if ax.images] == ["contact.mu = 0.1", "contact.mu = 0.2"]
    assert P.label(out, "contact.mu") == "contact.mu [-]\nwith contact.alpha_n [-]"


def test_failures_table_lists_each_failed_design_with_its_message(synthetic_report):
    _, _, page = synthetic_report
    failures = page.split("<h2>Failures</h2>", 1)[1].split("</section>", 1)[0]
    rows = re.findall(r"<tr>(<td>.*?)</tr>", failures)
    assert rows == [f"<td>4</td><td>4000</td><td>0.5</td><td>{MESSAGE}</td>"]


def test_pages_link_their_figures_and_hold_the_definition_and_chosen_designs(synthetic_report):
    """Truth: every figure in DIR/report/ is linked from the page (PNG and PDF) and the
    Markdown page links its PNGs; the study file is on the page; the chosen designs are
    the best of each objective, with their figures."""
    folder, _, page = synthetic_report
    markdown = (folder / "report.md").read_text()
    for p in (folder / FIGURES).glob("*.p[nd][gf]"):
        assert f"{FIGURES}/{p.name}" in page
    assert all(f"({FIGURES}/{p.name})" in markdown for p in (folder / FIGURES).glob("metric-*.png"))
    assert "<pre>" in page and html.escape('"load.q0" = [1000.0, 2000.0, 4000.0]') in page
    out = read_outcome(folder)
    # best ep_max_fraction: the smallest q0 x R2 (design 0); best stress: q0 / R2 least (design 1)
    assert best_designs(out) == {"ep_max_fraction": 0, "max_von_mises": 1}
    assert "Design 0: best ep_max_fraction (minimize)" in markdown
    assert "Design 1: best max_von_mises (minimize)" in markdown
    assert '"why":"best ep_max_fraction (minimize)"' in page
    for i in (0, 1):
        stem = f"design-{out.rows[i].key[:12]}"
        assert (folder / FIGURES / f"{stem}-assembly.png").is_file()
        assert (folder / FIGURES / f"{stem}-energies.png").is_file()


def test_pareto_front_is_the_undominated_designs(synthetic_report):
    folder, _, _ = synthetic_report
    out = read_outcome(folder)
    # minimise (q0 R2 / 1e4, 1e3 q0 / R2): at fixed q0 the two trade off, so the front
    # is every design not beaten in both by another: checked by brute force
    pts = {i: (r.metrics["ep_max_fraction"], r.metrics["max_von_mises"]) for i, r in enumerate(out.rows) if r.ok}
    brute = [i for i, p in pts.items() if not any(q[0] <= p[0] and q[1] <= p[1] and q != p for q in pts.values())]
    assert pareto_front(out) == brute and brute


def test_cli_writes_the_report_at_the_end_of_a_tiny_real_sweep(tmp_path, capsys):
    (tmp_path / "s.toml").write_text(
        'base = "ptfe-r05"\n[set]\n"time.t_end" = 2e-5\n'
        '[parameters]\n"load.q0" = [-1.0, 2e4]\n"layout.R2_ratio" = [0.5, 1.0]\n'
    )
    out = tmp_path / "out"
    assert main(["sweep", str(tmp_path / "s.toml"), "--out", str(out), "--workers", "1", "-q"]) == 1
    assert f"report: {out / PAGE}" in capsys.readouterr().out
    page = (out / PAGE).read_text()
    assert (out / "study.toml").read_text() == (tmp_path / "s.toml").read_text()
    # the two designs of the negative load fail with the scenario's own message
    failures = page.split("<h2>Failures</h2>", 1)[1].split("</section>", 1)[0]
    assert failures.count("load.q0") >= 2 and "must be &gt;= 0" in failures
    assert (out / FIGURES / "heatmap-ep_max_fraction.png").is_file()
    # the report again, from the folder alone
    assert main(["study", "report", str(out), "-q"]) == 0
    assert (out / PAGE).read_text() == page
    # the sweep again: nothing to compute, no cluster, nothing redrawn
    drawn = {
        p: p.stat().st_mtime_ns
        for p in [
            out / PAGE,
            out / "report.md",
            *(out / FIGURES).glob("*.p[nd][gf]"),
            *(out / "report_assets").iterdir(),
        ]
    }
    assert main(["sweep", str(tmp_path / "s.toml"), "--out", str(out), "--workers", "1", "-q"]) == 1
    assert "computed: 0," in capsys.readouterr().out
    assert {p: p.stat().st_mtime_ns for p in drawn} == drawn


def test_report_redraws_only_when_its_inputs_change(tmp_path):
    """Truth: the figures' files are kept (same mtimes) by a second report of the same
    folder, and drawn again once a design's metrics change (the hash beside them too)."""
    synthetic(tmp_path)
    write_report(tmp_path)
    figures = sorted((tmp_path / FIGURES).glob("*.png"))
    assert figures
    before = {p: p.stat().st_mtime_ns for p in figures}
    digest = (tmp_path / FIGURES / INPUTS_FILE).read_text()
    write_report(tmp_path)
    assert {p: p.stat().st_mtime_ns for p in figures} == before
    # design 0's metrics change: its record is written again with another value
    record = D.read_record(tmp_path, read_outcome(tmp_path).rows[0].key)
    record["summary"]["ep_max_fraction"] *= 2.0
    D.write_record(tmp_path, record)
    write_report(tmp_path)
    assert (tmp_path / FIGURES / INPUTS_FILE).read_text() != digest
    metric = tmp_path / FIGURES / "metric-ep_max_fraction.png"
    assert metric.stat().st_mtime_ns != before[metric]


def test_the_inputs_hash_follows_the_code_that_draws(tmp_path, monkeypatch):
    """Truth: the same study read back hashes alike, and differently once the source of the
    figures' module changes (a changed figure is redrawn within one version)."""
    from granplate.study import plots
    from granplate.study.report import inputs_hash

    synthetic(tmp_path)
    out = read_outcome(tmp_path)
    digest = inputs_hash(out)
    assert inputs_hash(read_outcome(tmp_path)) == digest
    edited = tmp_path / "plots.py"
    edited.write_bytes(Path(plots.__file__).read_bytes() + b"\n# a changed figure\n")
    monkeypatch.setattr(plots, "__file__", str(edited))
    assert inputs_hash(out) != digest


def test_report_of_a_folder_without_a_study_is_a_clear_error(tmp_path, capsys):
    assert main(["study", "report", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "study folder" in err and "results.nc" in err


# ------------------------------------------------------------------------- targets


def test_targets_judge_each_combination_of_the_choices():
    table = parse_report_table(
        {
            "conclusion": " In words. ",
            "targets": [
                {
                    "label": "stress",
                    "metric": ["max_von_mises", "max_von_mises_nodes"],
                    "value": 10.0,
                    "within": 0.1,
                    "where": {"case": "steel"},
                },
                {"label": "share", "metric": "ep_max_fraction", "value": 1.0, "within": 0.5, "where": {"case": "ptfe"}},
            ],
        },
        ("mesh", "case"),
    )
    targets = table.targets
    assert table.conclusion == "In words."
    assert targets[0].metrics == ("max_von_mises", "max_von_mises_nodes") and targets[1].within == 0.5
    designs = [{"mesh": m, "case": c} for m in (40, 80) for c in ("steel", "ptfe")]
    values = [
        {"max_von_mises": 8.0, "max_von_mises_nodes": 10.5},  # mesh 40 steel: nodes hold
        {"ep_max_fraction": 1.4},  # mesh 40 ptfe: holds
        {"max_von_mises": 8.5, "max_von_mises_nodes": 7.0},  # mesh 80 steel: neither
        {"ep_max_fraction": 1.6},
    ]  # mesh 80 ptfe: no
    rows = judge(targets, ("mesh", "case"), designs, values)
    assert [params for params, _ in rows] == [{"mesh": 40}, {"mesh": 80}]
    (_, (s40, p40)), (_, (s80, p80)) = rows
    assert (s40.design, s40.metric, s40.value, s40.holds) == (0, "max_von_mises_nodes", 10.5, True)
    assert (p40.design, p40.holds) == (1, True)
    assert (s80.metric, s80.holds) == ("max_von_mises", False)  # the closer of the two
    assert p80.holds is False
    # a parameter zipped with the one a target names is no choice: the same two groups
    zipped = [{**d, "ratio": 1.0 if d["case"] == "steel" else 0.5} for d in designs]
    assert [p for p, _ in judge(targets, ("mesh", "case", "ratio"), zipped, values)] == [{"mesh": 40}, {"mesh": 80}]


@pytest.mark.parametrize(
    "table, field",
    [
        ({"targets": [{"metric": "nope", "value": 1.0}]}, "report.targets[0].metric"),
        ({"targets": [{"metric": "ep_max_fraction", "value": 0.0}]}, "report.targets[0].value"),
        (
            {"targets": [{"metric": "ep_max_fraction", "value": 0.1, "where": {"x.y": 1}}]},
            "report.targets[0].where.x.y",
        ),
        ({"conclusions": "typo"}, "report.conclusions"),
    ],
)
def test_report_table_mistakes_name_the_field(table, field):
    with pytest.raises(ScenarioError) as err:
        parse_report_table(table, ("load.q0",))
    assert err.value.field == field


def test_page_judges_the_targets_and_draws_the_designs_that_meet_them(tmp_path):
    synthetic(tmp_path)
    # ep_max_fraction = q0 / 1e4 x R2 is 0.1 only for (q0 2000, R2 0.5): design 2
    (tmp_path / "study.toml").write_text(
        STUDY_TOML + '[report]\nconclusion = "Only one."\n'
        '[[report.targets]]\nmetric = "ep_max_fraction"\nvalue = 0.1\n'
        'within = 0.01\nwhere = {"layout.R2_ratio" = 0.5}\n'
    )
    out = read_outcome(tmp_path)
    assert target_designs(out) == [2]
    page = write_report(tmp_path).read_text()
    assert "1 of 3 combinations meet every target" in page and "<p>Only one.</p>" in page
    assert "Design 2: meets the targets" in (tmp_path / "report.md").read_text()
    assert '"why":"meets the targets' in page


LOG_TOML = """base = "ptfe-r05"
[set]
"time.t_end" = 1e-6
[parameters]
"materials.ptfe.E" = {range = [1e9, 1e10], num = 3, log = true}
"load.q0" = [1000.0, 2000.0, 4000.0]
"""


@pytest.fixture(scope="module")
def log_study(tmp_path_factory):
    """A sweep over a modulus in Pa spaced with log = true, and q0 in a plain list; the
    metrics are known functions of the two."""
    import tomllib

    folder = tmp_path_factory.mktemp("log-study")
    study = parse_study(tomllib.loads(LOG_TOML))
    keys = []
    for i, (E, q0) in enumerate(study.designs):
        text = gp.dumps(study.scenario(i))
        keys.append(D.design_key(text))
        summary = {"ep_max_fraction": q0 / 1e5 * (E / 1e9) ** 0.3, "max_von_mises": 1e4 * q0, "units": D.metric_units()}
        D.write_record(
            folder,
            D.make_record(keys[-1], study.changes(i), text, {"status": "ok", "summary": summary, "elapsed_s": 0.0}),
        )
    write_table(study, folder, keys)
    (folder / "study.toml").write_text(LOG_TOML)
    return read_outcome(folder)


def test_axis_labels_name_the_unit_of_the_values_drawn(log_study):
    """An axis labelled [MPa] carries values in MPa: the modulus 1e9..1e10 Pa is drawn at
    1e3..1e4 on the metric figure's x axis and in the heat map's tick labels."""
    out = log_study
    E_mpa = [1e3, 1e3 * 10**0.5, 1e4]
    fig = P.fig_metric(out, "ep_max_fraction")
    ax = next(a for a in fig.axes if a.get_xlabel().startswith("materials.ptfe.E"))
    assert ax.get_xlabel() == "materials.ptfe.E [MPa]"
    drawn = np.unique(np.concatenate([ln.get_xdata() for ln in ax.get_lines()]))
    np.testing.assert_allclose(drawn, E_mpa, rtol=1e-12)
    lo, hi = ax.get_xlim()
    assert lo < E_mpa[0] and E_mpa[-1] < hi < 1e5
    heat = P.fig_heatmap(out, "max_von_mises")
    panel = heat.axes[0]
    axis, ticks = (
        (panel.get_xlabel(), panel.get_xticklabels())
        if panel.get_xlabel().startswith("materials")
        else (panel.get_ylabel(), panel.get_yticklabels())
    )
    assert axis == "materials.ptfe.E [MPa]"
    np.testing.assert_allclose([float(t.get_text()) for t in ticks], E_mpa, rtol=1e-3)
    cells = sorted(float(t.get_text()) for t in panel.texts if t.get_gid() == "cell-max_von_mises")
    np.testing.assert_allclose(cells, sorted([10.0, 20.0, 40.0] * 3), rtol=1e-12)  # 1e4 q0 Pa in MPa


def test_log_parameters_are_drawn_on_log_axes(log_study):
    """A parameter spaced with log = true gets a log x axis (even over one decade); a plain
    list over a factor of 4 stays linear."""
    out = log_study
    assert out.log_parameters == frozenset({"materials.ptfe.E"})
    fig = P.fig_metric(out, "ep_max_fraction")
    scales = {ax.get_xlabel().split(" [")[0]: ax.get_xscale() for ax in fig.axes if ax.get_xlabel()}
    assert scales == {"materials.ptfe.E": "log", "load.q0": "linear"}


def test_heat_map_cells_are_legible(log_study):
    """The heat map is sized to its grid and its cell values and ticks are at least 8 pt
    (11 px at the saved DPI)."""
    heat = P.fig_heatmap(log_study, "max_von_mises")
    panel = heat.axes[0]
    sizes = [t.get_fontsize() for t in panel.texts] + [t.get_fontsize() for t in panel.get_xticklabels()]
    assert min(sizes) >= 8 and min(sizes) * P.DPI / 72 >= 11
    width, height = heat.get_size_inches()
    assert width >= P.HEAT_CELL[0] * 3 and height >= P.HEAT_CELL[1] * 3


def test_field_units_are_the_scenario_docs_units():
    """Every field the study pages give a unit has that unit in docs/scenario.md's tables
    ("-" there is "1" here), and an indexed path takes its field's ("plate.size[2]": m)."""
    import re
    from collections import defaultdict
    from pathlib import Path

    from granplate.study.table import FIELD_UNITS, field_unit

    doc = (Path(__file__).resolve().parent.parent / "docs" / "scenario.md").read_text()
    documented = defaultdict(set)
    for key, unit in re.findall(r"^\| `([A-Za-z_0-9]+)` \| ([^|]*?) \|", doc, flags=re.M):
        documented[key].add("1" if unit.strip() == "-" else unit.strip())
    checked = [k for k in FIELD_UNITS if k in documented]
    assert len(checked) >= 35
    for key in checked:
        assert documented[key] == {FIELD_UNITS[key]}, key
    assert (
        field_unit("plate.size[2]"),
        field_unit("plate.elements[0]"),
        field_unit("layout.layers[1].radius"),
        field_unit("layout.layers[0].count"),
    ) == ("m", "1", "m", "1")

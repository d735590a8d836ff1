"""The study's interactive page (granplate.study.explorer): the answer first, the study
file collapsed, plotly.js beside the page and no address off the machine, one data blob
equal to the study's table, units and log axes as the study gives them, WebGL and a page
under 20 MB for 10,000 designs, and the live page of a running sweep counting its
designs done, failed and left (`--watch`)."""

from __future__ import annotations

import html
import json
import re
from pathlib import Path

import numpy as np
import pytest

import granplate as gp
from granplate.cli import main
from granplate.study import design as D
from granplate.study import explorer as X
from granplate.study.constraints import Bound, is_feasible, violations
from granplate.study.outcome import Row, StudyOutcome, read_outcome
from granplate.study.report import PAGE, pareto_front, write_live_page, write_report
from granplate.study.watch import watch
from test_study_report import FAILED, LOG_TOML, STUDY_TOML, synthetic

#: Size of the large synthetic study, and the most bytes its page and blob may take.
LARGE = 10_000
MAX_PAGE_BYTES = 20_000_000


def blob(page: str, name: str = "study-data") -> dict:
    """The JSON of a <script type='application/json' id=name> element of a page."""
    text = re.search(rf"<script id='{name}' type='application/json'>(.*?)</script>", page, re.S).group(1)
    return json.loads(text.replace("<\\/", "</"))


def synthetic_outcome(n: int, folder: Path, seed: int = 0) -> StudyOutcome:
    """An optimisation of n trials whose metrics are known functions of its parameters
    (nothing simulated): a packing kind, a modulus in Pa on a log scale, a radius; the
    mass constrained to 0.1 .. 0.12 kg; some trials failed."""
    rng = np.random.default_rng(seed)
    bound = Bound("granular_mass", 0.10, 0.12)
    rows = []
    for i in range(n):
        kind = ("hexagonal", "square")[i % 2]
        E = float(10 ** rng.uniform(8.5, 11.5))
        r = float(rng.uniform(0.005, 0.01))
        metrics = {
            "ep_max_fraction": 0.1 + 0.3 * (r - 0.005) / 0.005 * (1.2 if kind == "square" else 1.0),
            "max_von_mises": 2e7 * (E / 1e10) ** 0.2 / (r / 0.005),
            "granular_mass": 0.08 + 4.0 * r + 0.01 * (kind == "square"),
            "dissipated_fraction": float(rng.uniform(0.2, 0.6)),
        }
        ok = i % 97 != 5
        rows.append(
            Row(
                i,
                {"layout.kind": kind, "materials.steel.E": E, "layout.R1": r},
                metrics if ok else {},
                "ok" if ok else "SimulationError: synthetic",
                f"{i:064x}",
                is_feasible(violations((bound,), metrics)) if ok else None,
            )
        )
    return StudyOutcome(
        folder,
        "optimization",
        "two-layer-base.toml",
        {},
        ("layout.kind", "materials.steel.E", "layout.R1"),
        rows,
        list(rows[0].metrics),
        D.metric_units(),
        objectives={"ep_max_fraction": "minimize", "max_von_mises": "minimize"},
        constraints=(bound,),
        log_parameters=frozenset({"materials.steel.E"}),
    )


@pytest.fixture(scope="module")
def sweep_page(tmp_path_factory):
    """The page of the synthetic 6-design sweep of the report's tests (one failure), with
    a conclusion."""
    folder = tmp_path_factory.mktemp("explorer")
    synthetic(folder)
    (folder / "study.toml").write_text(STUDY_TOML + '[report]\nconclusion = "The smallest load wins."\n')
    page = write_report(folder)
    return folder, page.read_text()


def test_first_screen_holds_the_answer_and_the_study_file_is_collapsed(sweep_page):
    """The conclusion is shown once (the study file, which also holds it, is inside a
    <details>), the best designs and the main figure come before the views to explore,
    and the study file is collapsed."""
    _, page = sweep_page
    answer, rest = page.split("<section id='explore'>", 1)
    assert "id='conclusion'" in answer and "id='best'" in answer and "id='fig-main'" in answer
    outside = re.sub(r"<details.*?</details>", "", page, flags=re.S)
    assert outside.count("The smallest load wins.") == 1
    study = re.search(r"<details id='study'>(.*?)</details>", page, re.S).group(1)
    assert html.escape('"load.q0" = [1000.0, 2000.0, 4000.0]') in study and "<pre>" in study
    assert "<pre>" not in re.sub(r"<details.*?</details>", "", rest, flags=re.S)


def test_page_is_offline_with_plotly_beside_it(sweep_page):
    """Every script and style is a file of report_assets/ beside the page (plotly.min.js
    the plotly package's own, its version and licence noted); no http(s) address is
    loaded; the PNG and PDF figures are still written and linked for papers."""
    folder, page = sweep_page
    sources = re.findall(r"<(?:script|link)[^>]*(?:src|href)='([^']+)'", page)
    assert sources and all(s.startswith(X.ASSETS + "/") for s in sources), sources
    assert not re.search(r"(?:src|href)=['\"]https?:", page)
    assets = folder / X.ASSETS
    assert (assets / X.PLOTLY_JS).read_bytes() == X.plotly_source().read_bytes()
    assert f"v{X.plotly_version()}" in (assets / X.PLOTLY_NOTE).read_text()
    assert "MIT" in (assets / X.PLOTLY_NOTE).read_text()
    for name in X.OWN_ASSETS:
        assert (assets / name).stat().st_size > 1000
    for kind in ("png", "pdf"):
        figs = sorted((folder / "report").glob(f"metric-*.{kind}"))
        assert figs and all(f"report/{p.name}" in page for p in figs)
    assert (folder / "report.md").read_text().startswith("# Study report")


def test_data_blob_equals_the_table(sweep_page):
    """The page's blob holds every design once, its parameters, metrics and status exactly
    as the study's table, and the counts of designs done, failed and left."""
    folder, page = sweep_page
    out = read_outcome(folder)
    data = blob(page)
    assert len(data["designs"]) == len(out.rows) == 6
    for d, r in zip(data["designs"], out.rows):
        assert (d["number"], d["key"], d["status"], d["ok"]) == (r.number, r.key, r.status, r.ok)
        assert d["params"] == r.params
        assert d["metrics"] == {m: v for m, v in r.metrics.items() if v is not None}
    assert data["counts"] == {"total": 6, "done": 5, "failed": 1, "left": 0, "infeasible": 0}
    assert data["designs"][FAILED]["metrics"] == {} and "synthetic failure" in data["designs"][FAILED]["status"]
    assert "6 designs: 5 done, 1 failed, 0 left" in page
    # the chosen designs link their figures, which are there
    best = [d for d in data["designs"] if d["best"]]
    assert best and all(d["figures"] for d in best)
    assert all((folder / f).is_file() for d in best for _, f in d["figures"])


def test_units_are_those_of_the_values_drawn(tmp_path):
    """A parameter in Pa is drawn in MPa and labelled [MPa]: the factor, the axis titles
    and the drawn values agree; a length stays in m; a text parameter has no unit."""
    out = synthetic_outcome(40, tmp_path)
    q = X.quantity(out, "materials.steel.E")
    assert (q["unit"], q["factor"], q["si_unit"]) == ("MPa", 1e-6, "Pa")
    assert X.quantity(out, "layout.R1")["unit"] == "m" and X.quantity(out, "max_von_mises")["unit"] == "MPa"
    fig = X.metric_figure(out, "max_von_mises")
    axes = {fig["layout"][k]["title"]["text"]: k for k in fig["layout"] if k.startswith("xaxis")}
    assert set(axes) == {"layout.kind", "materials.steel.E [MPa]", "layout.R1 [m]"}
    assert fig["layout"]["yaxis"]["title"]["text"] == "max_von_mises [MPa]"
    trace = next(t for t in fig["data"] if t["xaxis"] == "x" + axes["materials.steel.E [MPa]"][5:])
    for x, y, i in zip(trace["x"], trace["y"], trace["customdata"]):
        r = out.rows[i]
        assert x == pytest.approx(r.params["materials.steel.E"] * 1e-6, rel=1e-6)
        assert y == pytest.approx(r.metrics["max_von_mises"] * 1e-6, rel=1e-6)
    pareto = X.pareto_figure(out)
    assert pareto["layout"]["xaxis"]["title"]["text"] == "ep_max_fraction [-] (minimize)"
    assert pareto["layout"]["yaxis"]["title"]["text"] == "max_von_mises [MPa] (minimize)"


def test_log_parameters_are_on_log_axes(tmp_path):
    """A parameter spaced with log = true is on a log axis in every view that draws it
    (the metric panels; the parallel coordinates, as log10 with ticks at its values); the
    others are not."""
    out = synthetic_outcome(40, tmp_path)
    fig = X.metric_figure(out, "ep_max_fraction")
    types = {
        fig["layout"][k]["title"]["text"]: fig["layout"][k].get("type") for k in fig["layout"] if k.startswith("xaxis")
    }
    assert types == {"materials.steel.E [MPa]": "log", "layout.R1 [m]": None, "layout.kind": "category"}
    dims = {d["name"]: d for d in X.parcoords_figure(out)["data"][0]["dimensions"]}
    E = dims["materials.steel.E"]
    rows = X.parcoords_figure(out)["rows"]
    np.testing.assert_allclose(
        E["values"], [np.log10(out.rows[i].params["materials.steel.E"] * 1e-6) for i in rows], rtol=1e-6
    )
    assert [float(t) for t in E["ticktext"]] == pytest.approx([10**t for t in E["tickvals"]], rel=1e-2)
    assert "tickvals" not in dims["layout.R1"]
    assert dims["granular_mass"]["label"] == "granular_mass [kg] in 0.1 .. 0.12"


def test_log_study_of_the_report_tests_draws_the_modulus_on_a_log_axis_in_mpa(tmp_path):
    """The report tests' sweep over a modulus with log = true: its page's metric view
    has a log x axis labelled [MPa] whose values are the modulus / 1e6."""
    import tomllib

    from granplate.study.spec import parse_study
    from granplate.study.sweep import write_table

    study = parse_study(tomllib.loads(LOG_TOML))
    keys = []
    for i, (E, q0) in enumerate(study.designs):
        text = gp.dumps(study.scenario(i))
        keys.append(D.design_key(text))
        summary = {"ep_max_fraction": q0 / 1e5 * (E / 1e9) ** 0.3, "max_von_mises": 1e4 * q0, "units": D.metric_units()}
        D.write_record(
            tmp_path,
            D.make_record(keys[-1], study.changes(i), text, {"status": "ok", "summary": summary, "elapsed_s": 0.0}),
        )
    write_table(study, tmp_path, keys)
    (tmp_path / "study.toml").write_text(LOG_TOML)
    figures = blob(
        X.explorer_html(
            read_outcome(tmp_path),
            X.explorer_data(read_outcome(tmp_path)),
            X.explorer_figures(read_outcome(tmp_path)),
            [],
        ),
        "study-figures",
    )
    layout = figures["metric"]["layout"]
    axis = next(layout[k] for k in layout if k.startswith("xaxis") and "materials" in layout[k]["title"]["text"])
    assert axis["title"]["text"] == "materials.ptfe.E [MPa]" and axis["type"] == "log"
    xs = sorted(
        {x for t in figures["metric"]["data"] if t["xaxis"] == axis["anchor"].replace("y", "x") for x in t["x"]}
    )
    np.testing.assert_allclose(xs, [1e3, 1e3 * 10**0.5, 1e4], rtol=1e-6)


def test_pareto_view_has_every_feasible_design_and_the_front(tmp_path):
    """The front view's 'designs' trace holds every feasible completed design, the
    infeasible ones their own trace, the front trace is `pareto_front`, and each best
    design is named in the legend, not on the plot."""
    out = synthetic_outcome(300, tmp_path)
    fig = X.pareto_figure(out)
    by = {t["meta"]: t for t in fig["data"] if t["meta"] != "best"}
    feasible = [i for i, r in enumerate(out.rows) if r.ok and r.feasible]
    assert by["designs"]["customdata"] == feasible
    assert by["infeasible"]["customdata"] == [i for i, r in enumerate(out.rows) if r.ok and r.feasible is False]
    assert sorted(by["front"]["customdata"]) == sorted(pareto_front(out))
    best = [t for t in fig["data"] if t["meta"] == "best"]
    assert [t["name"].split(":")[0] for t in best] == ["best ep_max_fraction", "best max_von_mises"]
    assert "annotations" not in fig["layout"]


def test_a_large_study_is_webgl_and_its_page_stays_small(tmp_path):
    """10,000 designs: scatter views are WebGL (scattergl), the table is one blob, and the
    page is under 20 MB."""
    out = synthetic_outcome(LARGE, tmp_path)
    page = X.write_explorer(out, {}, [])
    size = page.stat().st_size
    assert size < MAX_PAGE_BYTES, size
    figures = blob(page.read_text(), "study-figures")
    kinds = {t["type"] for f in ("pareto", "metric") for t in figures[f]["data"]}
    assert kinds == {"scattergl"}
    assert len(blob(page.read_text())["designs"]) == LARGE
    small = synthetic_outcome(50, tmp_path)
    assert {t["type"] for t in X.pareto_figure(small)["data"]} == {"scatter"}


def _partial_sweep(folder: Path, done: int):
    """The synthetic sweep's folder while it runs: its study file and the records of its
    first `done` designs, no table yet."""
    synthetic(folder)
    for name in ("results.nc", "results.csv", "results.sha256"):
        (folder / name).unlink()
    out = read_outcome(folder, live=True)
    for r in out.rows[done:]:
        D.record_path(folder, r.key).unlink()
    return out


def test_live_page_counts_done_failed_and_left_and_reloads(tmp_path):
    """A sweep with 5 of its 6 records (one a failure) and no table: the page counts 4
    done, 1 failed, 1 left, and reloads itself; once the last record is in, `watch`
    writes the full report, which no longer reloads."""
    full = _partial_sweep(tmp_path / "full", 6)
    _partial_sweep(tmp_path / "run", 5)
    page, c = write_live_page(tmp_path / "run")
    assert (c["done"], c["failed"], c["left"]) == (4, 1, 1)
    text = page.read_text()
    assert "6 designs: 4 done, 1 failed, 1 left" in text and "http-equiv='refresh'" in text
    assert blob(text)["designs"][5]["status"] == "not run"
    lines: list[str] = []
    assert watch(tmp_path / "run", every=0.0, echo=lines.append, rounds=1)["left"] == 1
    assert lines == ["watch: 4 done, 1 failed, 1 left of 6"]
    assert "http-equiv='refresh'" not in page.read_text()  # stopped: the page holds still
    last = full.rows[5].key
    D.record_path(tmp_path / "run", last).write_bytes(D.record_path(tmp_path / "full", last).read_bytes())
    c = watch(tmp_path / "run", every=0.0, echo=lines.append)
    assert (c["done"], c["left"]) == (5, 0) and lines[-1] == "watch: 5 done, 1 failed, 0 left of 6"
    assert "http-equiv='refresh'" not in page.read_text() and (tmp_path / "run" / "report.md").is_file()


def test_cli_watch_of_a_finished_study_writes_the_report_and_says_the_counts(tmp_path, capsys):
    """`granplate study report DIR --watch` on a finished study: one look, the report, the
    counts; a bad --every is a one-line error naming it."""
    synthetic(tmp_path)
    assert main(["study", "report", str(tmp_path), "--watch", "--every", "0.01"]) == 0
    captured = capsys.readouterr().out
    assert "watch: 5 done, 1 failed, 0 left of 6" in captured and f"report: {tmp_path / PAGE}" in captured
    assert main(["study", "report", str(tmp_path), "--watch", "--every", "0"]) == 2
    assert "--every = 0.0: must be > 0" in capsys.readouterr().err


def test_watch_waits_for_an_optimisation_s_first_table_and_refuses_a_folder_without_a_study(tmp_path):
    """An optimisation's folder before its first trials.csv: `watch` says it waits (once)
    and writes nothing; a folder without a study file is the report's one-line error."""
    from granplate.errors import ScenarioError
    from granplate.study.watch import WAITING

    (tmp_path / "study.toml").write_text(
        'base = "ptfe-r05"\n[parameters]\n"load.q0" = {range = [1e3, 4e3]}\n'
        '[objectives]\n"ep_max_fraction" = "minimize"\n'
    )
    lines: list[str] = []
    assert watch(tmp_path, every=0.0, echo=lines.append, rounds=3)["total"] == 0
    assert lines == [WAITING] and not (tmp_path / PAGE).exists()
    with pytest.raises(ScenarioError, match="study folder"):
        watch(tmp_path / "nothing", every=0.0, rounds=1)

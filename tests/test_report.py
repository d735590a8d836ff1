"""The report's table is computed from the result datasets (change a dataset and the
table changes), missing runs are marked, and report.md / report.html are written with
the figures embedded."""

from __future__ import annotations

import base64
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import pytest

from granplate.results import analysis as an
from granplate.paper import report

from short_results import short_results


@pytest.fixture(scope="module")
def runs():
    return short_results()


def _row(rows, start):
    found = [r for r in rows if r.quantity.startswith(start)]
    assert len(found) == 1, f"{len(found)} rows start with {start!r}"
    return found[0]


def test_rows_show_the_runs_numbers(runs):
    """'ours' is each run's own number: E_shock, max von Mises, plate peak share."""
    rows = report.statements(runs)
    e_bare = float(runs["bare-plate"].E_shock[-1])
    r = _row(rows, "Shock energy put into the bare plate")
    assert r.ours_text == f"{e_bare:.3e} J"
    assert r.ratio == pytest.approx(e_bare / 1.53e-2)
    vm = float(runs["steel-r1"].max_von_mises.max())
    r = _row(rows, "Max von Mises stress with granules")
    assert r.ours_text == f"{vm / 1e6:.1f} MPa" and r.ratio == pytest.approx(vm / 80e6)
    peak = float(runs["steel-r1"].E_plate.max()) / float(runs["steel-r1"].E_shock[-1])
    r = _row(rows, "Plate energy peak, steel R2 = R1")
    assert r.ours_text == f"{100 * peak:.1f}%"
    assert r.holds == (0.45 <= peak <= 0.60)


def test_table_changes_with_the_data(runs):
    """Perturb a dataset: the affected rows follow, the others do not."""
    base = report.statements(runs)
    changed = dict(runs)
    steel = runs["steel-r1"].copy(deep=True)
    steel["E_plate"] = steel["E_plate"] * 2.0
    steel["max_von_mises"] = steel["max_von_mises"] * 0 + 80e6
    changed["steel-r1"] = steel
    rows = report.statements(changed)
    before = _row(base, "Plate energy peak, steel R2 = R1")
    after = _row(rows, "Plate energy peak, steel R2 = R1")
    assert after.ratio == pytest.approx(2.0 * before.ratio)
    vm = _row(rows, "Max von Mises stress with granules")
    assert vm.ours_text == "80.0 MPa" and vm.holds is True and vm.ratio == pytest.approx(1.0)
    assert _row(rows, "Shock energy put into the bare plate") == _row(base, "Shock energy put into the bare plate")


def test_ordering_statement_follows_the_data(runs):
    """Swap the weak and strong runs: 'share grows with intensity' no longer holds."""
    rows = report.statements(runs)
    swapped = dict(runs)
    swapped["ptfe-r05-weak"], swapped["ptfe-r05"] = (
        runs["ptfe-r05"].copy(deep=True),
        runs["ptfe-r05-weak"].copy(deep=True),
    )
    for ds in (swapped["ptfe-r05-weak"],):
        ds["E_plate"] = ds["E_plate"] + 0.5 * float(ds.E_shock[-1])  # the "weak" run now gives most to the plate
    r = _row(report.statements(swapped), "The plate's share grows with the shock intensity (peak share)")
    assert r.holds is False
    assert _row(rows, "The plate's share grows with the shock intensity (peak share)").ours_text != r.ours_text


def test_missing_runs_are_marked(runs):
    """A statement whose run is absent says so and is not judged."""
    rows = report.statements({"bare-plate": runs["bare-plate"]})
    r = _row(rows, "Max von Mises stress with granules")
    assert r.ours_text.startswith("not run") and r.holds is None
    assert _row(rows, "Shock energy put into the bare plate").holds is not None


def test_energy_balance_row_uses_every_run(runs):
    """The energy-balance row reports the worst residual over all runs."""
    worst = max(float(np.abs(d.energy_residual_max).max()) for d in runs.values())
    r = _row(report.statements(runs), "Energy balance")
    assert r.ours_text == f"max |residual| = {worst:.1e}"


def test_run_table_has_residual_and_wall_time(runs):
    """The run table shows each run's own residual, wall time and disc-averaged stress."""
    rows = report.run_rows(runs)
    assert [r[0] for r in rows] == list(runs)
    i_res = report.RUN_HEADER.index("max abs(energy residual)")
    i_wall = report.RUN_HEADER.index("wall time [s]")
    i_disc = report.RUN_HEADER.index("disc-averaged von Mises [MPa]")
    for r, ds in zip(rows, runs.values()):
        assert len(r) == len(report.RUN_HEADER)
        assert r[i_res] == f"{an.max_energy_residual(ds):.1e}"
        assert r[i_wall] == f"{an.run_info(ds)['wall_time_s']:.1f}"
        assert r[i_disc] == f"{float(ds.max_von_mises_disc.max()) / 1e6:.1f}"
    # a result written before the disc average existed shows "-", it does not crash
    old = {"steel-r1": runs["steel-r1"].drop_vars("max_von_mises_disc")}
    assert report.run_rows(old)[0][i_disc] == "-"


@dataclass
class _Record:
    name: str
    path: Path
    status: str = "ran"
    kind: str = "preset"


@dataclass
class _Outcome:
    runs: list = field(default_factory=list)
    figures: dict = field(default_factory=dict)
    animations: list = field(default_factory=list)
    seconds: float = 1.0


def test_write_report_md_and_html(runs, tmp_path):
    """report.md links the figures; report.html embeds them (base64) and opens alone."""
    from granplate.paper import plots
    from granplate.results.dataset import write

    recs = []
    for name, ds in runs.items():
        recs.append(_Record(name, write(ds, tmp_path / f"{name}.nc")))
    png, pdf = plots.save_figure(plots.fig_A1(runs["steel-r1"]), tmp_path / "figures", "figA1")
    md, page = report.write_report(tmp_path, _Outcome(runs=recs, figures={"A1": [png, pdf]}))
    text = md.read_text()
    assert "| # | statement | paper | ours | ratio | holds |" in text
    assert "figures/figA1.png" in text
    assert "shortened" in text  # the runs are 0.1 ms long and the report says so
    html = page.read_text()
    assert base64.b64encode(png.read_bytes()).decode()[:200] in html
    assert "<table>" in html and "src='figures/" not in html


def test_conclusions_follow_the_rows(runs):
    """The conclusions block says 'holds' only when every row behind it holds."""
    rows = report.statements(runs)
    lines = report.conclusions(rows)
    assert len(lines) == len(report.CONCLUSIONS)
    flipped = [replace(r, ours=10.0) if r.key == "vm_reduction" else r for r in rows]  # 10 > 0.5: fails
    assert "does not hold" in report.conclusions(flipped)[0]
    assert report.conclusions(report.statements({}))[0].split(": ")[1].startswith("not run")


def test_every_criterion_text_is_in_the_report(runs, tmp_path):
    """Each statement's criterion writes the text of the table's criterion column: the
    report shows it, with the reason, for every statement (thresholds typed once)."""
    from granplate.paper.statements import ENERGY_BALANCE, STATEMENTS
    from granplate.results.dataset import scenario_of

    blocks = report.build_report(runs, {})
    text = "\n".join(b.text for b in blocks) + "\n".join(" ".join(r) for b in blocks for r in b.rows)
    rows = report.statements(runs)
    assert all(n in runs for s in STATEMENTS for n in s.needs)
    for s in STATEMENTS:
        rule = s.criterion.text() + (f" ({s.why})" if s.why else "")
        assert rule in text, s.key
        assert _row(rows, s.text).rule == rule
    tol = float(scenario_of(runs["steel-r1"]).solver.energy_tol)
    assert ENERGY_BALANCE.criterion.text(tol) in text and f"= {tol:g}" in ENERGY_BALANCE.criterion.text(tol)


def test_every_sensitivity_run_is_discussed():
    """The discussion picks its checks by baseline and role from the records: each check
    run is in exactly one of its groups (none is typed in by name, none is forgotten)."""
    from granplate.paper import checks as ck
    from granplate.paper import discussion as dn

    groups = (
        list(dn.STRESS_CHECKS)
        + ck.runs_of(dn.STEEL, "sampling")
        + list(dn.PTFE_NUMERIC)
        + list(dn.PTFE_PLATE)
        + ck.runs_of(dn.BARE, "sampling", "mesh")
    )
    assert sorted(groups) == sorted(c.name for c in ck.CHECKS)
    with pytest.raises(ValueError, match="role"):
        ck.SensitivityRun("x", "steel-r1", role="colour")


@pytest.mark.parametrize("growth, settled", [(1.01, True), (1.3, False)])
def test_stress_discussion_quotes_the_disc_averaged_stress(runs, growth, settled):
    """The stress discussion gives the disc-averaged stress of the run and of each mesh
    check, and says it has settled only when every refinement moves it by < 5%."""
    from granplate.paper import discussion as dn

    steel = runs["steel-r1"]
    disc = float(steel["max_von_mises_disc"].max())
    checks = {}
    for k, name in enumerate(n for n in dn.STRESS_CHECKS if n.endswith(("ny80", "ny160"))):
        c = steel.copy(deep=True)
        c["max_von_mises_disc"] = c["max_von_mises_disc"] * growth ** (k + 1)
        checks[name] = c
    text = "\n".join(dn.stress_discussion(runs, checks))
    assert f"the largest stress is {disc / 1e6:.1f} MPa" in text
    assert f"disc mean {disc * growth / 1e6:.1f} MPa vs {disc / 1e6:.1f} MPa" in text
    assert ("barely moves with the mesh" in text) == settled
    assert ("refinements of +30.0%, +30.0%" in text) == (not settled)


def test_report_opens_on_the_verdict_counts(runs):
    """The block after the title is the summary: statements that hold, do not, are only
    reported, and the conclusions that hold, counted from the rows themselves."""
    rows = report.statements(runs)
    blocks = report.build_report(runs, {})
    first = blocks[1]
    assert first.kind == "summary" and first == report.verdict_summary(rows, runs, {})
    cards = {label: value for value, label, _ in first.rows}
    n_ok, n_bad = sum(r.holds is True for r in rows), sum(r.holds is False for r in rows)
    assert cards["statements hold"] == str(n_ok) and cards["do not hold"] == str(n_bad)
    assert cards["reported without a verdict"] == str(sum(r.holds is None for r in rows))
    n_concl = sum(h is True for _, h, _ in report.conclusion_verdicts(rows))
    assert cards["conclusions hold"] == f"{n_concl} / {len(report.CONCLUSIONS)}" and cards["runs"] == str(len(runs))
    assert first.text.startswith(f"{n_ok} of {n_ok + n_bad} judged statements hold")
    flipped = [replace(r, ours=10.0) if r.key == "vm_reduction" else r for r in rows]
    assert report.verdict_summary(flipped, runs, {}).rows[3][0] == f"{n_concl - 1} / {len(report.CONCLUSIONS)}"

"""`granplate reproduce --3d` and the report's section "The paper in 3D": the plan holds
the six 3D twins at DIR/3d/NAME.nc, the section's table is each pair of results' own
`summary`, the thin-limit verdicts are the criteria's (a difference past its target
fails), the figure draws each run's own plate share, and the report without --3d is
as before."""

from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr

from granplate.cli import main
from granplate.paper import plots, report
from granplate.paper import reproduce as rp
from granplate.paper import space as sp
from granplate.results.dataset import read, summary
from granplate.setup.presets import preset_names
from conftest import section_titles

T_END = 2e-5  # the shock half over: every code path of both dimensions, seconds of work


def fabricated(
    name: str, e_shock: float, peak: float, vm: float = 1e8, residual: float = 1e-6, wall: float = 1.0, n: int = 21
) -> xr.Dataset:
    """A small result with what `summary` reads: E_shock ramps to e_shock [J], the plate's
    energy rises to peak * e_shock and falls, the rest stays in the granules."""
    t = np.linspace(0.0, 1e-3, n)
    e = e_shock * np.minimum(1.0, t / 1e-4)
    ep = peak * e_shock * np.sin(np.pi * t / t[-1]) ** 2
    ep[n // 2] = peak * e_shock
    zero = np.zeros(n)
    return xr.Dataset(
        {
            "E_shock": ("time", e),
            "E_plate": ("time", ep),
            "E_granular": ("time", e - ep),
            "D_viscous": ("time", zero),
            "D_friction": ("time", zero),
            "D_plastic": ("time", zero),
            "max_von_mises": ("time", vm * np.sin(np.pi * t / t[-1])),
            "energy_residual_max": ("time", np.full(n, residual)),
        },
        coords={"time": t},
        attrs={
            "scenario_name": name,
            "granplate_version": "test",
            "run_info": json.dumps({"wall_time_s": wall, "n_steps": 100, "status": "ok"}),
        },
    )


@pytest.fixture(scope="module")
def pair():
    """2D results and 3D twins of the six presets, fabricated: the 3D ones 0.05% off in
    E_shock, 0.5% off in peak share, with their own stresses, residuals and wall times."""
    plane, space = {}, {}
    for k, n in enumerate(preset_names()):
        e, p = 1e-3 * (k + 1), 0.1 * (k + 1) / 6
        plane[n] = fabricated(n, e, p, vm=1e8 + k * 1e7, residual=1e-6, wall=2.0 + k)
        space[n] = fabricated("3d-" + n, e * 1.0005, p * 0.995, vm=9e7 + k * 1e7, residual=3e-7, wall=7.0 + 3 * k)
    return plane, space


def test_plan_with_3d_has_the_six_twins(tmp_path):
    """--3d adds one job per preset, its 3D twin "3d-NAME" shortened like it, at
    DIR/3d/NAME.nc; without --3d the plan has none."""
    jobs = [j for j in rp.plan(tmp_path, T_END, "none", False, space=True) if j.kind == "space"]
    assert [j.name for j in jobs] == [sp.twin_name(n) for n in preset_names()]
    assert [j.path for j in jobs] == [tmp_path / "3d" / f"{n}.nc" for n in preset_names()]
    for j, n in zip(jobs, preset_names()):
        assert j.scenario.name == "3d-" + n and j.scenario.dimension == 3
        assert j.scenario.time.t_end == T_END and sp.twin_preset(j.name) == n
    assert not [j for j in rp.plan(tmp_path, T_END, "fast") if j.kind == "space"]
    assert sp.twin_preset("plastic/steel-r1") is None and sp.twin_preset("steel-r1") is None


def test_cli_help_names_3d(capsys):
    """`granplate reproduce --help` offers --3d."""
    with pytest.raises(SystemExit):
        main(["reproduce", "--help"])
    assert "--3d" in capsys.readouterr().out


def test_case_table_is_each_pairs_summary(pair):
    """Each cell is 2D / 3D from gp.summary of the two Datasets, the differences (3D - 2D) / 2D,
    the wall-time ratio 3D / 2D; changing a 3D result changes its row."""
    plane, space = pair
    h = sp.CASE_HEADER
    col = h.index
    rows = {r[0]: r for r in sp.case_table(plane, space)}
    assert list(rows) == preset_names()
    for n in preset_names():
        a, b = summary(plane[n]), summary(space[n])
        r = rows[n]
        assert r[col("E_shock 2D / 3D [J]")] == f"{a['e_shock']:.4e} / {b['e_shock']:.4e}"
        assert r[col("E_shock 3D vs 2D")] == f"{100 * (b['e_shock'] / a['e_shock'] - 1):+.2f}%" == "+0.05%"
        assert r[col("plate peak 2D / 3D")] == (
            f"{100 * a['ep_max_fraction']:#.4g}% / {100 * b['ep_max_fraction']:#.4g}%"
        )
        assert r[col("plate peak 3D vs 2D")] == "-0.50%"
        assert r[col("max von Mises 2D / 3D [MPa]")] == (
            f"{a['max_von_mises'] / 1e6:.1f} / {b['max_von_mises'] / 1e6:.1f}"
        )
        assert r[col("max abs(energy residual) 2D / 3D")] == "1.0e-06 / 3.0e-07"
        assert r[col("wall time 2D / 3D [s]")] == f"{a['wall_time_s']:.1f} / {b['wall_time_s']:.1f}"
        assert r[col("wall time 3D / 2D")] == f"{b['wall_time_s'] / a['wall_time_s']:.1f}"
    changed = dict(space)
    changed["steel-r1"] = space["steel-r1"].copy(deep=True)
    changed["steel-r1"]["E_plate"] = changed["steel-r1"]["E_plate"] * 1.1
    new = {r[0]: r for r in sp.case_table(plane, changed)}["steel-r1"]
    assert new[col("plate peak 3D vs 2D")] == f"{100 * (0.995 * 1.1 - 1):+.2f}%"


def test_verdict_fails_when_a_difference_passes_its_target():
    """E_shock 2% off (target 1%) fails, a peak share 1% off (target 2%) holds, 3% off fails:
    the verdicts are the criteria's, the table's and the paragraph's."""
    plane = {"steel-r1": fabricated("steel-r1", 1e-3, 0.5)}
    cases = {"steel-r1": fabricated("3d-steel-r1", 1.02e-3, 0.505)}
    checks = sp.thin_limit_checks(plane, cases)
    verdicts = {c.key: c.holds for _, c in checks}
    assert verdicts == {"steel-r1:e_shock": False, "steel-r1:ep_max_fraction": True}
    assert [r[-1] for r in sp.check_table(checks)] == ["no", "yes"]
    assert "**1 of 2 differences are within" in sp.verdict_text(checks)
    assert "steel-r1 E_shock (+2.00%)" in sp.verdict_text(checks)
    assert checks[0][1].rule == "E_shock within 1% of the 2D run's"
    worse = sp.thin_limit_checks(plane, {"steel-r1": fabricated("3d-steel-r1", 1.005e-3, 0.515)})
    assert [c.holds for _, c in worse] == [True, False]
    assert [t.tol for t in sp.TARGETS] == [0.01, 0.02]


def test_figure_draws_each_runs_plate_share(pair):
    """One panel per preset; its curves are the 2D and the 3D run's own E_p / E_shock over
    time [ms], both axes with units."""
    plane, space = pair
    names = preset_names()
    fig = plots.fig_3d(*[plane[n] for n in names], *[space[n] for n in names])
    axes = [ax for ax in fig.axes if ax.get_visible()]
    assert len(axes) == len(names)
    lines = {ln.get_gid(): ln for ax in axes for ln in ax.get_lines()}
    for n in names:
        for tag, ds in (("2d", plane[n]), ("3d", space[n])):
            ln = lines[f"plate:{tag}:{n}"]
            np.testing.assert_allclose(ln.get_xdata(), ds.time.values * 1e3)
            np.testing.assert_allclose(ln.get_ydata(), ds.E_plate.values / ds.E_shock.values[-1])
        assert lines[f"plate:2d:{n}"].get_linestyle() == "-" and lines[f"plate:3d:{n}"].get_linestyle() == "--"
    assert all(ax.get_xlabel() == "time [ms]" and ax.get_ylabel().endswith("[-]") for ax in axes)
    spec = plots.figure_spec(sp.FIGURE_KEY)
    assert spec.presets == (*names, *(sp.twin_name(n) for n in names))
    assert plots.figure_stem(sp.FIGURE_KEY) == "fig-3d"
    assert sp.FIGURE_KEY not in plots.report_figures(plastic=True)
    assert sp.FIGURE_KEY in plots.report_figures(plastic=False, space=True)


def test_section_holds_the_table_and_the_verdicts(pair):
    """The section is the case table, the thin-limit checks (all within their targets
    here) and the twins' runs; no twins, no section."""
    plane, space = pair
    blocks = sp.section(plane, space)
    assert blocks[0].kind == "h2" and blocks[0].text == "The paper in 3D"
    tables = {b.header: b.rows for b in blocks if b.kind == "table"}
    assert tables[sp.CASE_HEADER] == tuple(sp.case_table(plane, space))
    assert [r[-1] for r in tables[sp.CHECK_HEADER]] == ["yes"] * 12
    assert any("**12 of 12 differences are within" in b.text for b in blocks if b.kind == "p")
    assert any(b.kind == "details" and "6 runs" in b.text for b in blocks)
    assert sp.section(plane, {}) == []


@pytest.fixture(scope="module")
def run3d(tmp_path_factory):
    out = tmp_path_factory.mktemp("repro3d")
    outcome = rp.reproduce(
        out, t_end=T_END, workers=2, checks="none", plastic=False, space=True, animations=False, quiet=True
    )
    return out, outcome


def test_reproduce_3d_writes_the_twins_and_the_section(run3d):
    """reproduce --3d runs the six presets and their 3D twins (DIR/3d/NAME.nc), draws fig-3d
    and writes the section, whose E_shock and plate-peak cells are the stored results'
    summaries."""
    out, outcome = run3d
    assert outcome.ok, outcome.problems
    assert {r.name for r in outcome.runs if r.kind == "space"} == {sp.twin_name(n) for n in preset_names()}
    for n in preset_names():
        ds = read(out / "3d" / f"{n}.nc")
        assert ds.attrs["scenario_name"] == "3d-" + n and ds.time.values[-1] == pytest.approx(T_END)
    assert (out / "figures" / "fig-3d.png").stat().st_size > 0 and (out / "figures" / "fig-3d.pdf").is_file()
    md = (out / "report.md").read_text()
    assert "## Contacts that yield" not in md
    section = md.split("## The paper in 3D")[1]
    for n in preset_names():
        a, b = summary(read(out / f"{n}.nc")), summary(read(out / "3d" / f"{n}.nc"))
        row = next(line for line in section.splitlines() if line.startswith(f"| {n} |"))
        assert f"| {a['e_shock']:.4e} / {b['e_shock']:.4e} |" in row
        assert f"| {100 * a['ep_max_fraction']:#.4g}% / {100 * b['ep_max_fraction']:#.4g}% |" in row
    assert "fig-3d.png" in section


def test_second_reproduce_3d_reuses_the_twins(run3d):
    """Nothing changed: the twins are reused, no file rewritten; without --3d the report
    has no 3D section."""
    out, outcome = run3d
    stamps = {r.name: r.path.stat().st_mtime_ns for r in outcome.runs}
    again = rp.reproduce(
        out,
        t_end=T_END,
        workers=1,
        checks="none",
        plastic=False,
        space=True,
        figures=False,
        animations=False,
        quiet=True,
    )
    assert again.ok and {r.status for r in again.runs} == {"reused"}
    assert {r.name: r.path.stat().st_mtime_ns for r in again.runs} == stamps
    assert "## The paper in 3D" in (out / "report.md").read_text()
    assert "fig-3d.png" in (out / "report.md").read_text()  # the earlier figure, still current
    plain = rp.reproduce(
        out, t_end=T_END, workers=1, checks="none", plastic=False, figures=False, animations=False, quiet=True
    )
    assert {r.kind for r in plain.runs} == {"preset"}
    assert "The paper in 3D" not in (out / "report.md").read_text()


def test_report_has_the_section_only_with_3d(run3d):
    """build_report, given the stored results, adds "The paper in 3D" when given the 3D
    twins, and not without them."""
    out, _ = run3d
    plane = {n: read(out / f"{n}.nc") for n in preset_names()}
    space = {n: read(out / "3d" / f"{n}.nc") for n in preset_names()}
    assert "The paper in 3D" not in section_titles(report.build_report(plane, {}))
    blocks = report.build_report(plane, {}, space=space)
    assert "The paper in 3D" in section_titles(blocks)
    tables = [b for b in blocks if b.kind == "table" and b.header == sp.CASE_HEADER]
    assert len(tables) == 1 and tables[0].rows == tuple(sp.case_table(plane, space))

"""`granplate reproduce` end to end on shortened runs (all figures, both animations, the
report with the cases rerun with yielding contacts), reuse of unchanged results (a second
run simulates nothing; a changed scenario or version is run again), `--no-plastic`, and
the plot / animate / export commands."""

from __future__ import annotations

import pytest

from granplate.version import __version__
from granplate.paper import plastic as pl
from granplate.paper import reproduce as rp
from granplate.cli import main
from granplate.paper.plots import EXTRA_FIGURES, FIGURES, figure_stem
from granplate.setup.presets import preset, preset_names
from granplate.results.dataset import read, summary, write

from short_results import short_results

T_END = 4e-5  # shock over (1e-5 s), wave inside the packing: every code path, seconds of work


@pytest.fixture(scope="module")
def first(tmp_path_factory):
    out = tmp_path_factory.mktemp("repro")
    outcome = rp.reproduce(out, t_end=T_END, workers=2, frames=3, quiet=True)
    return out, outcome


def test_reproduce_makes_everything(first):
    """Six presets, the fast checks and five yielding twins per law run; 8 figures (PNG + PDF),
    2 animations, report."""
    out, outcome = first
    assert outcome.ok, outcome.problems
    assert {r.name for r in outcome.runs if r.kind == "preset"} == set(preset_names())
    for law, folder in pl.TWIN_LAWS.items():
        assert {r.name for r in outcome.runs if r.kind == folder} == {pl.twin_name(n, law) for n in pl.twin_presets()}
    assert all(r.status == "ran" for r in outcome.runs)
    for name in preset_names():
        assert read(out / f"{name}.nc").time.values[-1] == pytest.approx(T_END)
    for name in pl.twin_presets():
        for law, folder in pl.TWIN_LAWS.items():
            twin = read(out / folder / f"{name}.nc")
            assert twin.time.values[-1] == pytest.approx(T_END) and set(twin.pair_normal_law.values) == {law}
    for key in [*FIGURES, *EXTRA_FIGURES]:
        assert (out / "figures" / f"{figure_stem(key)}.png").stat().st_size > 0
        assert (out / "figures" / f"{figure_stem(key)}.pdf").stat().st_size > 0
    assert sorted(p.stem for p in outcome.animations) == ["ptfe-r05", "steel-r05"]
    assert all(p.stat().st_size > 0 for p in outcome.animations)
    md = (out / "report.md").read_text()
    assert "The paper's statements and ours" in md and "Where we differ from the paper" in md
    assert "## Contacts that yield" in md
    assert (out / "report.html").read_text().count("data:image/png;base64,") == len(FIGURES) + len(EXTRA_FIGURES)


def test_yielding_section_shows_the_twins_summaries(first):
    """The section's row of each case carries gp.summary of its stored twin: plate peak
    share and D_plastic / E_shock."""
    out, _ = first
    md = (out / "report.md").read_text().split("## Contacts that yield")[1]
    for name in pl.twin_presets():
        e, y = summary(read(out / f"{name}.nc")), summary(read(out / "plastic" / f"{name}.nc"))
        m = summary(read(out / "johnson" / f"{name}.nc"))
        row = next(line for line in md.splitlines() if line.startswith(f"| {name} |"))
        shares = " / ".join(f"{100 * x['ep_max_fraction']:.1f}%" for x in (e, y, m))
        assert f"| {shares} |" in row
        assert f"| {100 * y['plastic_fraction']:.1f}% / {100 * m['plastic_fraction']:.1f}% |" in row
    assert "bare-plate (its own twin)" in md


def test_second_run_reuses_everything(first):
    """Nothing changed: every result is reused, no file is rewritten."""
    out, outcome = first
    stamps = {r.name: r.path.stat().st_mtime_ns for r in outcome.runs}
    again = rp.reproduce(out, t_end=T_END, workers=2, figures=False, animations=False, quiet=True)
    assert again.ok and {r.status for r in again.runs} == {"reused"}
    assert {r.name: r.path.stat().st_mtime_ns for r in again.runs} == stamps


def test_changed_scenario_or_version_runs_again(first):
    """A stored result whose scenario or version differs is run again; the rest reused."""
    out, _ = first
    path = out / "steel-r1.nc"
    ds = read(path)
    ds.attrs["scenario_toml"] = ds.attrs["scenario_toml"].replace("q0 = 50000.0", "q0 = 40000.0")
    write(ds, path)
    ds2 = read(out / "ptfe-r05-weak.nc")
    ds2.attrs["granplate_version"] = "0.0.0-old"
    write(ds2, out / "ptfe-r05-weak.nc")
    again = rp.reproduce(out, t_end=T_END, workers=2, checks="none", figures=False, animations=False, quiet=True)
    status = {r.name: r.status for r in again.runs}
    assert status.pop("steel-r1") == "ran" and status.pop("ptfe-r05-weak") == "ran"
    assert set(status.values()) == {"reused"}
    assert rp.is_current(path, rp.preset_scenario("steel-r1", T_END))


def test_is_current(tmp_path):
    """is_current compares the stored scenario TOML and version with a new run's."""
    ds = short_results()["steel-r05"]
    path = write(ds, tmp_path / "r.nc")
    scenario = rp.preset_scenario("steel-r05", float(ds.time[-1]))
    assert rp.is_current(path, scenario)
    assert not rp.is_current(path, rp.preset_scenario("steel-r05", 2 * float(ds.time[-1])))
    assert not rp.is_current(path, rp.preset_scenario("steel-r1", float(ds.time[-1])))
    assert not rp.is_current(tmp_path / "missing.nc", scenario)
    (tmp_path / "junk.nc").write_text("not netCDF")
    assert not rp.is_current(tmp_path / "junk.nc", scenario)
    assert rp.expected_identity(scenario)[1] == __version__


def test_shortened_keeps_intervals_valid():
    s = rp.shortened(preset("steel-r1"), 5e-7)
    assert s.time.t_end == 5e-7 and s.time.output_interval == 5e-7 and s.time.field_interval == 5e-7
    s = rp.shortened(preset("steel-r1"), 1e-5)
    assert s.time.field_interval == s.time.output_interval
    assert rp.shortened(preset("steel-r1"), None) == preset("steel-r1")


def test_plan_checks_modes(tmp_path):
    """--checks picks the sensitivity runs; the twins come with every mode, or not at all."""
    names = lambda mode, plastic=False: {j.name for j in rp.plan(tmp_path, 1e-5, mode, plastic)}  # noqa: E731
    assert names("none") == set(preset_names())
    twins = {pl.twin_name(n, law) for law in pl.TWIN_LAWS for n in pl.twin_presets()}
    assert names("none", True) == set(preset_names()) | twins
    assert names("fast") < names("all")
    with pytest.raises(Exception):
        rp.plan(tmp_path, None, "sometimes")


def test_no_plastic_leaves_the_twins_out(first, capsys):
    """`--no-plastic`: no twin runs, no yielding figure, and the report has no section."""
    out, _ = first
    assert (
        main(
            [
                "reproduce",
                "--out",
                str(out),
                "--t-end",
                str(T_END),
                "--checks",
                "none",
                "--no-plastic",
                "--no-figures",
                "--no-animations",
                "-q",
            ]
        )
        == 0
    )
    assert "runs: 0 ran, 6 reused" in capsys.readouterr().out
    md = (out / "report.md").read_text()
    assert "## Contacts that yield" not in md and "fig-yielding" not in md
    assert "The paper's statements and ours" in md


def test_cli_plot_animate_export(first, tmp_path, capsys):
    """The single-piece commands work on reproduce's results."""
    out, _ = first
    assert main(["plot", str(out), "--figure", "3", "--out", str(tmp_path)]) == 0
    assert (tmp_path / "fig3.png").is_file() and (tmp_path / "fig3.pdf").is_file()
    assert (
        main(["plot", str(out / "steel-r05.nc"), str(out / "ptfe-r05.nc"), "--figure", "fig7", "--out", str(tmp_path)])
        == 0
    )
    assert main(["plot", str(out / "steel-r1.nc"), "--figure", "A.1", "--out", str(tmp_path)]) == 0
    capsys.readouterr()
    assert main(["animate", str(out / "ptfe-r05.nc"), "-o", str(tmp_path / "a.gif"), "--frames", "2"]) == 0
    assert (tmp_path / "a.gif").stat().st_size > 0
    assert "/2 [" in capsys.readouterr().err  # the frames' progress bar on stderr (out of 2; its last refresh is timed)
    assert main(["animate", str(out / "ptfe-r05.nc"), "-o", str(tmp_path / "b.gif"), "--frames", "2", "-q"]) == 0
    assert "frame" not in capsys.readouterr().err
    assert main(["export", str(out / "steel-r1.nc"), "--vtk", str(tmp_path / "vtk")]) == 0
    assert (tmp_path / "vtk" / "steel-r1.pvd").is_file()


@pytest.mark.parametrize(
    "argv",
    [
        ["plot", "NOPE.nc", "--figure", "3"],
        ["plot", "{out}/steel-r1.nc", "--figure", "9"],
        ["plot", "{out}/steel-r1.nc", "--figure", "3"],  # needs two results
        ["plot", "{out}/report.md", "--figure", "A1"],  # not a result
        ["animate", "NOPE.nc"],
        ["animate", "{out}/steel-r1.nc", "-o", "x.avi"],
        ["export", "NOPE.nc", "--vtk", "v"],
    ],
)
def test_cli_user_mistakes_exit_2(first, argv, capsys):
    """A user's mistake prints one line and exits 2, no traceback."""
    out, _ = first
    assert main([a.format(out=out) for a in argv]) == 2
    err = capsys.readouterr().err
    assert err.startswith("granplate: error:") and "Traceback" not in err


def test_failed_run_keeps_partial_result(tmp_path):
    """A run that breaks (here: an impossible energy tolerance) is reported as failed, its
    partial result kept as NAME.partial.nc, and nothing is written under NAME.nc."""
    from granplate.setup.io import with_changes

    s = with_changes(preset("steel-r1"), {"solver.energy_tol": 1e-16, "time.t_end": 2e-5})
    rec = rp.run_job(rp.Job("bad", s, tmp_path / "bad.nc"))
    assert rec.status == "failed" and "energy" in rec.message
    assert (tmp_path / "bad.partial.nc").is_file() and not (tmp_path / "bad.nc").exists()

"""The verification suite (granplate.verification): every fast case passes against its
independent reference, the page is written, `granplate verify` exits non-zero on failure."""

from __future__ import annotations

import dataclasses
import json
import math
from importlib import resources

import pytest

from granplate import cli
from granplate import verification as V
from granplate.verification import base
from granplate.verification.base import Case, CaseResult, Check, Context

#: Checks that fail by design of the model, with the reason (docs/validation.md says why).
KNOWN_FAILURES: dict[tuple[str, str], str] = {}


@pytest.fixture(scope="module")
def ctx(tmp_path_factory) -> Context:
    return Context(out=tmp_path_factory.mktemp("verify"))


#: The fast cases in space (the 3D granules and the elastic solid): their own test file,
#: tests/test_verification_space.py, so that the suite's two workers share the cases.
SPACE_CASES = tuple(n for n in V.case_names(full=False) if n.startswith(("3d-", "lammps-3d", "solid-")))

#: Fast cases that a test file of their own runs whole (every check and the figure), so
#: that the suite runs each once.
OWN_FILE = {"plastic-impact": "tests/test_plastic_cases.py"}


@pytest.mark.parametrize("name", [n for n in V.case_names(full=False) if n not in SPACE_CASES + tuple(OWN_FILE)])
def test_fast_case(name, ctx):
    """Each fast case in the plane runs, draws its figure and passes every check (except
    the known, explained model-form failures, which must still fail exactly as documented)."""
    assert_case_passes(name, ctx)


def assert_case_passes(name: str, ctx: Context) -> None:
    """Case `name` runs, draws its figure and passes every check but its KNOWN_FAILURES."""
    result = base.run_case(V.get_case(name), ctx)
    assert result.crashed is None, result.crashed
    assert result.checks, "a case must check something"
    assert result.figure and (ctx.figure_dir / result.figure).is_file()
    for c in result.checks:
        assert c.why and c.source, c
    failing = {(name, c.quantity) for c in result.checks if not c.passed}
    expected = {k for k in KNOWN_FAILURES if k[0] == name}
    assert failing == expected, [(c.quantity, c.ours, c.reference, c.tolerance) for c in result.checks if not c.passed]


#: Quick cases whose checks are run without drawing (plate, contacts, conservation).
CHECKS_ONLY = ("patch-test", "newmark-elongation", "force-gradient")


def test_checks_run_without_matplotlib(tmp_path):
    """A case computes and checks in its run and draws in its draw: with figures off, the
    checks of a few quick cases run and pass in a fresh process that never imports
    matplotlib, and no figure is written."""
    import subprocess
    import sys

    code = (
        "import sys, json\n"
        "from pathlib import Path\n"
        "from granplate import verification as V\n"
        "from granplate.verification.base import Context, run_case\n"
        f"ctx = Context(out=Path({str(tmp_path)!r}), figures=False)\n"
        f"results = [run_case(V.get_case(n), ctx) for n in {CHECKS_ONLY!r}]\n"
        "print(json.dumps({'matplotlib': sorted(m for m in sys.modules if m.split('.')[0] == 'matplotlib'),"
        " 'results': [[r.name, r.crashed, len(r.checks), r.passed, r.figure] for r in results]}))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stderr
    report = json.loads(done.stdout.strip().splitlines()[-1])
    assert report["matplotlib"] == []
    for name, crashed, n_checks, passed, figure in report["results"]:
        assert crashed is None and n_checks > 0 and passed and figure is None, (name, crashed)
    assert not (tmp_path / base.FIGURE_DIR).exists()


def test_every_case_draws_from_its_own_numbers():
    """Every registered case has a draw function: its figure is drawn apart from its checks."""
    cases = V.all_cases()
    assert cases and all(c.draw is not None for c in cases), [c.name for c in cases if c.draw is None]


def test_slow_cases_are_only_in_the_full_suite():
    """--full adds the coupled convergence study; the fast suite leaves it out."""
    assert "coupled-convergence" in V.case_names(full=True)
    assert "coupled-convergence" not in V.case_names(full=False)
    assert len(set(V.case_names(full=True))) == len(V.case_names(full=True))


def test_check_kinds():
    """rel / abs / max / min checks compute their error and verdict as documented."""
    assert Check("q", "-", 2.0, "s", 2.002, 1e-3, "w").passed
    assert not Check("q", "-", 2.0, "s", 2.01, 1e-3, "w").passed
    assert Check("q", "-", 0.5, "s", 0.52, 0.03, "w", kind="abs").passed
    assert Check("q", "-", 0.0, "s", 1e-12, 1e-10, "w", kind="max").passed
    assert not Check("q", "-", 0.0, "s", 1e-9, 1e-10, "w", kind="max").passed
    assert Check("q", "-", 1.0, "s", 1.7, 1.0, "w", kind="min").passed
    assert not Check("q", "-", 1.0, "s", 0.5, 1.0, "w", kind="min").passed
    assert not Check("q", "-", 1.0, "s", math.nan, 1.0, "w").passed
    with pytest.raises(ValueError):
        Check("q", "-", 1.0, "s", 1.0, 1.0, "w", kind="other")


def test_scenario_files_are_package_data_and_valid():
    """Every verification scenario ships with the package and passes validation."""
    from granplate.model.arrays import build_model

    names = base.scenario_names()
    assert {"chung-ooi-1-glass", "striker-chain", "free-assembly"} <= set(names)
    for n in names:
        assert (resources.files("granplate.verification") / "scenarios" / f"{n}.toml").is_file()
        s = base.load_case_scenario(n)
        assert s.name == n
        build_model(s)


def test_page_is_written(tmp_path):
    """run_suite writes validation.md, .html, .json and the figures, with the table."""
    results = V.run_suite(tmp_path, names=["patch-test", "newmark-elongation"])
    assert all(r.passed for r in results)
    md = (tmp_path / "validation.md").read_text()
    assert "| case | quantity | reference | source | ours | error | tolerance | result |" in md
    assert "patch-test" in md and "newmark-elongation" in md and "Tolerances:" in md
    assert "validation-figures/patch-test.png" in md
    html = (tmp_path / "validation.html").read_text()
    assert html.startswith("<!DOCTYPE html>") and "newmark-elongation" in html
    data = json.loads((tmp_path / "validation.json").read_text())
    assert [c["name"] for c in data["cases"]] == ["patch-test", "newmark-elongation"]
    for r in results:
        assert (tmp_path / "validation-figures" / r.figure).is_file()


def _fake(monkeypatch, run):
    case = Case("fake", "plate", "A fake case", run)
    monkeypatch.setattr(V, "all_cases", lambda: (case,))


def test_cli_exit_status(tmp_path, monkeypatch):
    """`granplate verify` exits 0 when every check passes, 1 when one fails or a case crashes."""

    def good(ctx):
        return CaseResult.of("d", [Check("x", "-", 1.0, "s", 1.0, 1e-9, "w")])

    def bad(ctx):
        return CaseResult.of("d", [Check("x", "-", 1.0, "s", 2.0, 1e-9, "w")])

    def crash(ctx):
        raise RuntimeError("boom")

    for run, status in ((good, 0), (bad, 1), (crash, 1)):
        _fake(monkeypatch, run)
        assert cli.main(["verify", "--out", str(tmp_path), "-q"]) == status
    md = (tmp_path / "validation.md").read_text()
    assert "boom" in md and "FAIL" in md
    assert cli.main(["verify", "--out", str(tmp_path), "--case", "nonexistent"]) == 2
    assert cli.main(["verify", "--out", str(tmp_path), "--full", "--workers", "0"]) == 2


def test_long_runs_are_every_slow_run_once():
    """The runs computed ahead on Dask are exactly the distinct runs the slow cases read."""
    from granplate.verification import conservation, coupled, long_runs

    keys = [coupled.cache_key(s) for s in long_runs.long_runs()]
    wanted = {coupled.cache_key(s) for _, _, s in coupled.study_scenarios()}
    wanted |= {coupled.cache_key(s) for _, s in conservation.full_runs()}
    assert len(keys) == len(set(keys)) and set(keys) == wanted


def test_long_runs_on_dask_are_kept_and_then_only_read(tmp_path, monkeypatch):
    """Runs computed on a 2-worker cluster land in the page's run cache and the run store
    with the summary an in-process run gives (to round-off of the stress: the workers use
    one BLAS thread); a second pass computes nothing and the cases' study_run reads them."""
    from distributed import Client, LocalCluster

    from granplate.setup.io import with_changes
    from granplate.setup.presets import preset
    from granplate.verification import coupled, long_runs

    runs = [with_changes(preset(n), {"solver.scheme": "paper", "time.t_end": 2e-5}) for n in ("ptfe-r05", "bare-plate")]
    monkeypatch.setattr(long_runs, "long_runs", lambda: runs)
    monkeypatch.setenv("GRANPLATE_CACHE", str(tmp_path / "store"))  # an empty run store (the workers inherit it)
    ctx = Context(out=tmp_path, full=True, run_cache={})
    with (
        LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster,
        Client(cluster) as client,
    ):
        assert long_runs.compute_missing(ctx, client=client) == 2
        assert long_runs.compute_missing(ctx, client=client) == 0
    stored = json.loads((tmp_path / "validation-runs.json").read_text())
    assert set(stored) == {coupled.cache_key(s) for s in runs}
    here = [coupled.run_summary(s) for s in runs]
    monkeypatch.setattr(coupled, "run_summary", lambda s: pytest.fail("computed again"))
    for s, ref in zip(runs, here):
        got = coupled.study_run(Context(out=None, full=True, run_cache=None), s)  # from the run store
        assert got == stored[coupled.cache_key(s)]
        assert got["n_steps"] == ref["n_steps"] > 0 and got["e_shock"] == ref["e_shock"]
        for k in ("ep_max_fraction", "max_von_mises", "energy_residual_max"):
            assert got[k] == pytest.approx(ref[k], rel=1e-9, abs=1e-300), k


def test_observed_orders_and_richardson_recover_a_known_rate():
    """Q_h = Q + C h^p sampled at h, h/2, h/4, h/8 gives back p and Q (the plate mesh study's
    arithmetic, granplate.verification.plate_mesh)."""
    from granplate.verification.plate_mesh import convergence_table, observed_orders, richardson

    q = [1.5 + 0.3 * (0.5**k) ** 2.0 for k in range(4)]
    orders = observed_orders(q)
    assert orders == pytest.approx([2.0, 2.0], rel=1e-9)
    assert richardson(q, orders[-1]) == pytest.approx(1.5, rel=1e-12)
    table = convergence_table(
        "q", [("q", "-", q, 1.0), ("wobbly", "-", [1.0, 0.9, 0.95, 0.94], 1.0)], ((1, 1), (2, 2), (4, 4), (8, 8))
    )
    assert "| q [-] | 1.8 | 1.575 | 1.51875 | 1.5046875 | p = 2.00, 2.00 | 1.5 |" in table
    assert "(not monotone) | - |" in table


def _results() -> list[CaseResult]:
    """A passing case with long tolerance reasons and a failing one with a note and a table."""
    why = "a reason long enough to be collapsed on the page " * 20
    good = CaseResult(
        "good",
        "plate",
        "A good case",
        "Runs well.",
        [Check(f"x{i}", "m", 1.0, "closed form", 1.0, 1e-9, why) for i in range(3)],
        notes=["a short note"],
        seconds=1.5,
    )
    bad = CaseResult(
        "bad",
        "granular",
        "A bad case",
        "Runs badly.",
        [Check("y", "-", 1.0, "theory", 2.0, 1e-3, "short"), Check("z", "-", 1.0, "theory", 1.0, 1e-3, "short")],
        notes=["why it fails " * 100],
        tables=["| h | v |\n|---|---|\n| 1 | 2 |"],
        seconds=20.0,
    )
    return [good, bad]


def test_page_opens_on_the_counts_then_the_failures_then_the_cases():
    """First screen: the summary with the counts, then the failing checks alone, the case
    table, every check; long tolerance reasons collapsed, short ones shown, a failing
    case's notes shown however long."""
    from granplate.verification import page

    blocks = page.page_blocks(_results(), full=False, seconds=21.5, generated="Made for a test.")
    assert blocks[1].kind == "summary" and blocks[1].text == "2 cases, 5 checks: 1 of 5 checks fail, in 1 of 2 cases."
    assert blocks[1].rows[:3] == (
        ("1 / 2", "cases pass", "no"),
        ("4 / 5", "checks pass", "no"),
        ("1", "check fails", "no"),
    )
    h2 = [b.text for b in blocks if b.kind == "h2"]
    assert h2[:3] == ["Failures", "Cases", "Results"]
    tables = [b for b in blocks if b.kind == "table"]
    assert [r[1] for r in tables[0].rows] == ["y"] and len(tables[2].rows) == 5
    assert tables[1].rows == (
        ("[good](#good)", "A good case", "3", "0", "1.5", "pass"),
        ("[bad](#bad)", "A bad case", "2", "1", "20.0", "**FAIL**"),
    )
    collapsed = [b for b in blocks if b.kind == "details"]
    assert [b.text for b in collapsed] == ["Tolerances: the reason for each (3 checks)"]
    assert any(b.text == "Tolerances:" for b in blocks) and any(b.kind == "quote" for b in blocks)
    assert any(b.kind == "quote" and b.text.startswith("why it fails") for b in blocks), (
        "a failing case's notes stay open"
    )


def test_render_only_rebuilds_the_pages_from_the_json(tmp_path, capsys):
    """`granplate verify --render-only` writes the same pages from validation.json, running
    no case; without the JSON it says so in one line (exit 2)."""
    from granplate.verification import page

    page.write_pages(tmp_path, _results(), full=True, seconds=21.5)
    md, html = (tmp_path / "validation.md").read_text(), (tmp_path / "validation.html").read_text()
    (tmp_path / "validation.md").unlink()
    (tmp_path / "validation.html").unlink()
    assert cli.main(["verify", "--out", str(tmp_path), "--render-only"]) == 0
    assert (tmp_path / "validation.md").read_text() == md and (tmp_path / "validation.html").read_text() == html
    results, full, seconds, generated = page.read_results(tmp_path / "validation.json")
    assert [r.as_dict() for r in results] == [r.as_dict() for r in _results()] and full and seconds == 21.5
    capsys.readouterr()
    assert cli.main(["verify", "--out", str(tmp_path / "none"), "--render-only"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--render-only" in err and "validation.json not found" in err
    assert cli.main(["verify", "--out", str(tmp_path), "--render-only", "--case", "patch-test"]) == 2
    assert capsys.readouterr().err == "granplate: error: --render-only runs no case: --case cannot go with it\n"


def test_update_puts_refreshed_cases_in_place_and_keeps_the_rest(tmp_path, capsys):
    """`verify --case X --update` replaces X's result in validation.json, keeps every other
    case, puts a registered case in the registry's order (cases it does not know last), and
    says in the provenance line which cases were refreshed."""
    from granplate.verification import page

    old = _results()
    page.write_pages(tmp_path, old, full=True, seconds=21.5, generated="Made for a test.")
    assert cli.main(["verify", "--out", str(tmp_path), "--case", "patch-test", "--update", "-q"]) == 0
    results, full, seconds, generated = page.read_results(tmp_path / "validation.json")
    assert [r.name for r in results] == ["patch-test"] + [r.name for r in old]
    assert [r.as_dict() for r in results[1:]] == [r.as_dict() for r in old] and full and seconds == 21.5
    assert generated.startswith("Made for a test. Refreshed by") and "`patch-test`" in generated
    assert "patch-test" in (tmp_path / "validation.md").read_text()
    renamed = page.merge_results(results, [dataclasses.replace(results[0], title="again")])
    assert [r.title for r in renamed][0] == "again" and len(renamed) == len(results)
    assert cli.main(["verify", "--out", str(tmp_path), "--case", "patch-test", "--update", "-q"]) == 0
    again = page.read_results(tmp_path / "validation.json")[3]
    assert again.count("Refreshed by") == 1, "a case refreshed again keeps only its latest note"
    capsys.readouterr()
    assert cli.main(["verify", "--out", str(tmp_path), "--update"]) == 2
    assert "--update" in capsys.readouterr().err

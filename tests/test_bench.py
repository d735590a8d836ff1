"""The benchmark harness on one tiny case: the JSON report has every documented key."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def documented_keys() -> dict[str, set[str]]:
    """Keys of the docs/benchmarks.md's JSON tables, per section ('top', 'compile', 'results')."""
    text = (ROOT / "docs" / "benchmarks.md").read_text()
    keys: dict[str, set[str]] = {}
    section = None
    for line in text.splitlines():
        m = re.match(r"^###\s+JSON:\s+(\w+)", line)
        if m:
            section = m.group(1)
            keys[section] = set()
            continue
        if line.startswith("## "):
            section = None
        m = re.match(r"^\|\s*`([A-Za-z_0-9]+)`", line)
        if section and m:
            keys[section].add(m.group(1))
    return keys


def main(argv: list[str]) -> int:
    """`granplate bench ARGV` through granplate.bench's own parser (independent of cli.py)."""
    import argparse

    from granplate.bench import cli as bench

    parser = argparse.ArgumentParser(prog="granplate")
    bench.register(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(argv)
    return int(args.func(args))


def test_bench_json_has_documented_keys(tmp_path, monkeypatch):
    from granplate.bench import harness as h

    monkeypatch.setenv("GRANPLATE_CACHE", str(tmp_path))
    out = tmp_path / "bench.json"
    rc = main(["bench", "--cases", "bare-plate", "--t-end", "1e-5", "--repeats", "1", "--json", str(out)])
    assert rc == 0
    report = json.loads(out.read_text())
    keys = documented_keys()
    assert set(keys) == {"top", "compile", "results", "study"}
    assert keys["top"] <= set(report), keys["top"] - set(report)
    assert set(report["compile"]) == set(report["schemes"])
    for c in report["compile"].values():
        assert keys["compile"] <= set(c), keys["compile"] - set(c)
    assert len(report["results"]) == len(report["schemes"])
    for r in report["results"]:
        assert keys["results"] <= set(r), keys["results"] - set(r)
        assert set(r["rel_error"]) == set(h.METRICS)
        assert r["n_steps"] > 0 and r["dt_min_s"] > 0
    # the reference was cached on disk, keyed by the scenario
    assert list((tmp_path / "bench-reference").glob("bare-plate-*.json"))


def test_bench_unknown_case_is_a_user_error(capsys):
    assert main(["bench", "--cases", "no-such-preset"]) == 2
    assert "unknown case" in capsys.readouterr().err


def test_bench_of_a_3d_twin_says_why_not_and_where_instead(capsys):
    """A 3D twin (a preset `granplate run` knows) is refused by the scheme benchmark with
    one line that says why and names the twins' bench, before anything runs."""
    assert main(["bench", "--quick", "--cases", "steel-r1,3d-steel-r1"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("granplate: error: case(s) 3d-steel-r1: 3D twins") and err.count("\n") == 1
    assert "bench --twins" in err and "unknown" not in err


def test_scaling_rows_are_measured_and_documented(tmp_path):
    """`bench --scaling` on a 2 x 3 packing (5 granules, 7 touching pairs): one row per
    friction, every documented key, a small error against the RK4 reference, and LAMMPS
    reaching the same accuracy where it is installed."""
    from granplate.bench import scaling
    from granplate.verification import lammps as L

    out = tmp_path / "scaling.json"
    assert main(["bench", "--scaling", "--sizes", "2x3", "--t-end", "4e-6", "--json", str(out)]) == 0
    rows = json.loads(out.read_text())
    assert [r["mu"] for r in rows] == list(scaling.FRICTIONS)
    text = (ROOT / "docs" / "benchmarks.md").read_text().split("### Scaling JSON")[1]
    documented = {
        k
        for line in text.splitlines()
        if line.startswith("| `")
        for k in re.findall(r"`([a-z_0-9]+)`", line.split("|")[1])
    }
    for r in rows:
        assert {"granules", "contacts", "setup_s", "loop_s", "n_steps", "rss_peak_mib"} <= documented
        assert set(r) - {"lammps"} <= documented | {"error"}, set(r) - documented
        assert r["granules"] == 5 and r["contacts"] == 7 and r["n_steps"] > 0
        assert r["us_per_contact_step"] == pytest.approx(1e6 * r["loop_s"] / (r["n_steps"] * 7))
        assert r["energy_residual"] < 1e-6
    assert 0.0 < rows[0]["error"] < 1e-5
    lm = rows[0]["lammps"]
    if L.unavailable():
        assert "skipped" in lm
    else:
        assert lm["reached"] and lm["error"] <= rows[0]["error"]


def test_scaling_sizes_are_checked(capsys):
    """A malformed --sizes item or a non-positive --t-end is a user error naming it and
    the allowed values, before anything runs."""
    from granplate.bench import scaling

    assert scaling.granule_count(100, 100) == 9950 and scaling.granule_count(4, 3) == 10
    assert main(["bench", "--scaling", "--sizes", "4x3,ten"]) == 2
    assert "--sizes item 'ten'" in capsys.readouterr().err
    assert main(["bench", "--scaling", "--sizes", "4x3", "--t-end", "0"]) == 2
    assert "--t-end 0.0: must be > 0" in capsys.readouterr().err


def test_scaling_in_space_rows_are_measured_and_documented(tmp_path):
    """`bench --scaling --dimension 3` on one FCC cell (4 mutually touching spheres, 6 pairs):
    one row per friction with `dimension` 3 and every documented key, a small error against
    the RK4 reference, and LAMMPS's 3D run reaching the same accuracy where it is installed."""
    from granplate.bench import scaling
    from granplate.verification import lammps as L

    out = tmp_path / "scaling3.json"
    assert (
        main(["bench", "--scaling", "--dimension", "3", "--sizes", "1x1x1", "--t-end", "4e-6", "--json", str(out)]) == 0
    )
    rows = json.loads(out.read_text())
    assert [r["mu"] for r in rows] == list(scaling.FRICTIONS)
    text = (ROOT / "docs" / "benchmarks.md").read_text().split("### Scaling in space JSON")[1].split("\n## ")[0]
    documented = {
        k
        for line in text.splitlines()
        if line.startswith("| `")
        for k in re.findall(r"`([a-z_0-9]+)`", line.split("|")[1])
    }
    lammps_keys = set(
        re.findall(r"`([a-z_0-9]+)`", next(line for line in text.splitlines() if line.startswith("| `lammps`")))
    )
    for r in rows:
        assert set(r) - {"lammps"} <= documented, set(r) - documented
        assert r["dimension"] == 3 and r["cells"] == [1, 1, 1]
        assert r["granules"] == 4 and r["contacts"] == 6 and r["n_steps"] > 0
        assert r["us_per_contact_step"] == pytest.approx(1e6 * r["loop_s"] / (r["n_steps"] * 6))
        assert r["cpu_us_per_contact_step"] == pytest.approx(1e6 * r["loop_cpu_s"] / (r["n_steps"] * 6))
        assert r["energy_residual"] < 1e-6
    assert 0.0 < rows[0]["error"] < 1e-5
    lm = rows[0]["lammps"]
    if L.unavailable():
        assert "skipped" in lm
    else:
        assert set(lm) <= lammps_keys, set(lm) - lammps_keys
        assert lm["reached"] and lm["error"] <= rows[0]["error"]
        assert lm["cpu_us_per_contact_step"] == pytest.approx(1e6 * lm["cpu_s"] / (lm["n_steps"] * 6))


def test_scaling_in_space_mindlin_rows_run_lammps_at_our_step():
    """The 3D table's rows under Mindlin's law (`--scheme verlet --friction-law mindlin`): the
    packing takes LAMMPS's torque arms, and LAMMPS under the same law at granplate's step
    (`_lammps_same_law_worker`, in process here) is one algorithm with ours: the velocities at
    t_end agree to round-off (where LAMMPS is installed); its keys are documented."""
    from granplate.bench import scaling_space as S
    from granplate.results.run import simulate
    from granplate.verification import lammps as L

    s = S.launched_fcc((1, 1, 1), mu=0.099, t_end=4e-6, scheme="verlet", law="mindlin")
    assert s.contact.torque_arm == "lammps" and S.same_law("mindlin", "verlet") and not S.same_law("tanh", "verlet")
    ds = simulate(s, progress=False)
    final = {k: ds[k].values[-1].tolist() for k in ("vx", "vy", "vz")}
    spec = {"cells": [1, 1, 1], "mu": 0.099, "t_end": 4e-6, "scheme": "verlet", "law": "mindlin"}
    lm = S._lammps_same_law_worker({**spec, "dt_s": float(s.time.dt_max), "final": final, "repeats": 2})
    if L.unavailable():
        assert "skipped" in lm
        return
    assert len(lm["loop_s_runs"]) == 2 and lm["loop_s"] == min(lm["loop_s_runs"])  # the faster of the middle two
    text = (ROOT / "docs" / "benchmarks.md").read_text().split("### Scaling in space JSON")[1].split("\n## ")[0]
    line = next(line for line in text.splitlines() if line.startswith("| `lammps`"))
    assert set(lm) <= set(re.findall(r"`([a-z_0-9]+)`", line)), lm
    assert lm["n_steps"] == int(ds.attrs["n_steps"]) and lm["error"] is None
    assert lm["agreement"] < 1e-12 and S.lammps_error(lm).startswith("same step and law")


def test_scaling_in_space_rows_past_the_reference_run_lammps_at_our_step():
    """A frictionless row too big for the RK4 reference (as 10^6 spheres are; here one cell
    marked so) keeps its velocities at t_end under velocity Verlet, and LAMMPS at granplate's
    step is one algorithm with ours: the velocities agree to round-off (where LAMMPS is
    installed). Its output times fall on its steps, which LAMMPS does not cut (2 us of 40 ns
    steps in 10 intervals, not 20). Under the implicit scheme no such row runs LAMMPS."""
    from granplate.bench import scaling_space as S
    from granplate.verification import lammps as L

    assert S.lammps_at_our_step(0.0, "tanh", "verlet", big=True)
    assert not S.lammps_at_our_step(0.0, "tanh", "verlet", big=False)  # (halved to the reference's error)
    assert not S.lammps_at_our_step(0.0, "tanh", "implicit", big=True)
    assert not S.lammps_at_our_step(0.1, "tanh", "verlet", big=True)
    assert S.lammps_at_our_step(0.1, "mindlin", "verlet", big=True)
    assert S.outputs_on_steps(2e-6, 4e-8, 20) == 10 and S.outputs_on_steps(2e-5, 4e-8, 20) == 20
    spec = {"cells": [1, 1, 1], "mu": 0.0, "t_end": 2e-6, "scheme": "verlet", "law": "tanh", "reference": "skip"}
    row = S._ours_worker({**spec, "outputs": 20})
    assert row["n_steps"] == round(2e-6 / row["dt_s"]) == 50  # (20 output times would cut 10 steps)
    assert "error" not in row and "reference" not in row and len(row["final"]["vx"]) == 4
    assert max(abs(v) for v in row["final"]["vy"]) > 0.05  # (the launched plane has pushed the others aside)
    lm = S._lammps_same_law_worker({**spec, "dt_s": row["dt_s"], "final": row["final"]})
    if L.unavailable():
        assert "skipped" in lm
        return
    assert lm["n_steps"] == row["n_steps"] and lm["agreement"] < 1e-12


def test_scaling_in_space_options_are_checked(capsys):
    """In space --sizes takes FCC cells NXxNYxNZ; --dimension is 2 or 3; --scheme is any
    registered scheme (model.inputs.SCHEME_NAMES), another a user error naming them all;
    --friction-law mindlin only under --scheme verlet (where Mindlin's law runs)."""
    from granplate.bench import scaling, scaling_space
    from granplate.model.inputs import SCHEME_NAMES

    assert scaling_space.sphere_count((14, 14, 13)) == 10192
    assert [scaling_space.sphere_count(c) for c in scaling_space.SIZES] == [12, 108, 1008, 2916, 10192]
    assert main(["bench", "--scaling", "--dimension", "3", "--sizes", "4x3"]) == 2
    assert "--sizes item '4x3': allowed NXxNYxNZ" in capsys.readouterr().err
    assert main(["bench", "--scaling", "--dimension", "4"]) == 2
    assert "--dimension 4: allowed 2" in capsys.readouterr().err
    assert all(scaling.check_scheme(name) is None for name in SCHEME_NAMES)
    assert main(["bench", "--scaling", "--dimension", "3", "--scheme", "no-such"]) == 2
    assert f"--scheme 'no-such': allowed {', '.join(SCHEME_NAMES)}" in capsys.readouterr().err
    assert main(["bench", "--scaling", "--dimension", "3", "--mu", "0,-1"]) == 2
    assert "--mu item '-1': allowed numbers from 0 to 1000" in capsys.readouterr().err
    assert (
        scaling_space.parse_frictions("0, 0.5") == (0.0, 0.5)
        and scaling_space.parse_frictions(None) == scaling.FRICTIONS
    )
    assert main(["bench", "--scaling", "--dimension", "3", "--friction-law", "mindlin", "--scheme", "implicit"]) == 2
    assert "--friction-law mindlin: runs under --scheme verlet only" in capsys.readouterr().err
    assert main(["bench", "--scaling", "--dimension", "3", "--repeats", "0"]) == 2
    assert "--repeats 0: allowed integers from 1" in capsys.readouterr().err
    runs = [(0.9, "a"), (0.5, "b"), (1.7, "c"), (0.7, "d"), (0.8, "e")]
    assert scaling_space.median_run(runs) == (0.8, "e") and scaling_space.median_run(runs[:4]) == (0.7, "d")
    assert scaling_space.mu_law({"mu": 0.099, "law": "mindlin"}) == "0.099 (mindlin)"
    assert scaling_space.mu_law({"mu": 0.0, "law": "-"}) == "0"


def test_launched_fcc_is_a_touching_fcc_packing():
    """The 3D table's packing: 4 spheres per cell, 12 touching neighbours inside, no walls,
    the first lattice plane (x smallest) moving at 1 m/s and the rest at rest."""
    import numpy as np

    from granplate.bench.scaling_space import launched_fcc
    from granplate.model.arrays import build_model

    s = launched_fcc((3, 3, 3), mu=0.099)
    assert len(s.granules) == 108 and s.walls == () and s.dimension == 3 and s.contact.mu == 0.099
    x = np.array([g.x for g in s.granules])
    moving = np.array([g.vx for g in s.granules]) == 1.0
    assert moving.sum() == 18 and np.allclose(x[moving], x.min())
    m = build_model(s)
    assert np.bincount(m.pairs.ravel(), minlength=108).max() == 12


def test_bench_friction_table_runs_every_case(capsys, monkeypatch, tmp_path):
    """`granplate bench --friction --t-end 2e-7` (on a 4 x 6 packing) prints a row per case
    and, where LAMMPS is installed, the loop time, steps, cost per contact and step (loop /
    (steps x listed contacts)) and error of granplate ("split" and "verlet") and LAMMPS,
    and their ratios; the JSON has the documented keys."""
    from granplate.bench import friction
    from granplate.verification import lammps as L

    monkeypatch.setitem(friction.PACKING, "columns", 4)
    monkeypatch.setitem(friction.PACKING, "rows", 6)
    monkeypatch.setattr(friction, "REPEATS", 1)
    out_json = tmp_path / "friction.json"
    assert main(["bench", "--friction", "--t-end", "2e-7", "--json", str(out_json)]) == 0
    out = capsys.readouterr().out
    assert out.count("packing 22, mu") == 3 and out.count("ptfe-r05, q0 1e7") == 2
    report = json.loads(out_json.read_text())
    assert len(report["rows"]) == 5 and "final" not in report["rows"][0]
    cmp = report["lammps"]
    if L.unavailable():
        assert "skipped" in cmp and "LAMMPS comparison skipped" in out
        return
    assert "loop time granplate / LAMMPS" in out
    text = (ROOT / "docs" / "benchmarks.md").read_text().split("### Friction JSON")[1]
    documented = {
        k
        for line in text.splitlines()
        if line.startswith("| `")
        for k in re.findall(r"`([a-z_0-9]+)`", line.split("|")[1])
    }
    assert set(cmp) <= documented and set(cmp["granplate"]) <= documented, set(cmp["granplate"]) - documented
    assert set(cmp["lammps"]) <= documented and set(cmp["verlet"]) <= documented
    assert cmp["loop_ratio"] == pytest.approx(cmp["granplate"]["loop_s"] / cmp["lammps"]["loop_s"])
    assert cmp["cpu_ratio"] == pytest.approx(cmp["granplate"]["loop_cpu_s"] / cmp["lammps"]["loop_cpu_s"])
    assert cmp["verlet_cpu_ratio"] == pytest.approx(cmp["verlet"]["loop_cpu_s"] / cmp["lammps"]["loop_cpu_s"])
    assert "verlet / LAMMPS" in out
    for r in (cmp["granplate"], cmp["verlet"], cmp["lammps"]):
        assert r["n_steps"] > 0 and r["error_m_s"] >= 0.0
        assert r["us_per_contact_step"] == pytest.approx(1e6 * r["loop_s"] / (r["n_steps"] * cmp["contacts"]))
        assert r["cpu_us_per_contact_step"] == pytest.approx(1e6 * r["loop_cpu_s"] / (r["n_steps"] * cmp["contacts"]))


def test_bench_study_json_has_documented_keys(tmp_path):
    """`granplate bench --study` on a tiny study: every design computed, the JSON has every
    documented key, and the shares are consistent (loop + overhead = the whole)."""
    out = tmp_path / "study.json"
    assert main(["bench", "--study", "--designs", "4", "--workers", "2", "--t-end", "1e-5", "--json", str(out)]) == 0
    report = json.loads(out.read_text())
    keys = documented_keys()["study"]
    assert keys == set(report), keys ^ set(report)
    assert report["designs"] == report["designs_ok"] == 4 and report["workers"] == 2
    assert report["loop_share"] * (1.0 + report["overhead_vs_loop"]) == pytest.approx(1.0)
    assert 0.0 < report["loop_vs_task_median"] <= 1.0 and report["task_cpu_s_median"] > 0


def test_lammps_accuracy_counts_round_off_as_equal():
    """The same Verlet at the same step reaches our error to round-off: no halving for that,
    but an error larger by a part in a million is not as accurate."""
    from granplate.bench.scaling import as_accurate

    ours = 3.071253142543362e-05
    assert as_accurate(3.071253142600261e-05, ours)  # measured: 2e-14 relative above ours
    assert as_accurate(0.5 * ours, ours)
    assert not as_accurate(ours * (1 + 1e-6), ours)


def test_twins_rows_are_measured_and_documented(tmp_path):
    """`bench --twins` on ptfe-r05-weak shortened: one row whose keys are the documented
    ones, its differences and ratios the quotients of its own figures, and the verdicts
    the targets' (bench.twins.THIN_LIMIT, SPEED_TARGET) applied to them; the twin on the
    implicit scheme too, with eq. (11) held."""
    from granplate.bench import twins

    out = tmp_path / "twins.json"
    assert (
        main(["bench", "--twins", "--cases", "ptfe-r05-weak", "--t-end", "2e-5", "--repeats", "1", "--json", str(out)])
        == 0
    )
    (row,) = json.loads(out.read_text())
    text = (ROOT / "docs" / "benchmarks.md").read_text().split("(`granplate bench --twins`)")[1]
    documented = set(re.findall(r"`([a-z_0-9]+)`", text.split("*JSON*")[1].split("\n## ")[0]))
    assert set(row) <= documented, set(row) - documented
    assert row["case"] == "ptfe-r05-weak" and row["t_end_s"] == 2e-5 and row["n_steps_3d"] > 0
    assert row["e_shock_rel_diff"] == pytest.approx(row["e_shock_3d_j"] / row["e_shock_2d_j"] - 1.0)
    assert row["wall_ratio"] == pytest.approx(row["wall_3d_s"] / row["wall_2d_s"])
    assert row["within_speed_target"] == (row["wall_ratio"] <= twins.SPEED_TARGET)
    assert row["within_thin_limit"] == (
        abs(row["e_shock_rel_diff"]) <= twins.THIN_LIMIT["e_shock"]
        and abs(row["ep_max_fraction_rel_diff"]) <= twins.THIN_LIMIT["ep_max_fraction"]
    )
    # the same twin on the implicit scheme: its own steps, its figures' quotients
    assert row["n_steps_3d_implicit"] > 0 and row["n_steps_3d_implicit"] != row["n_steps_3d"]
    assert row["e_shock_implicit_rel_diff"] == pytest.approx(row["e_shock_3d_implicit_j"] / row["e_shock_2d_j"] - 1.0)
    assert row["wall_ratio_implicit"] == pytest.approx(row["wall_3d_implicit_s"] / row["wall_2d_s"])
    assert row["energy_residual_3d_implicit"] < 1e-4


def test_twins_options_are_checked(capsys):
    """An unknown case, a non-positive --t-end or --repeats is a user error naming it."""
    assert main(["bench", "--twins", "--cases", "3d-ptfe-r05"]) == 2
    assert "--cases 3d-ptfe-r05: unknown" in capsys.readouterr().err
    assert main(["bench", "--twins", "--t-end", "0"]) == 2
    assert "--t-end 0.0: must be > 0" in capsys.readouterr().err
    assert main(["bench", "--twins", "--repeats", "0"]) == 2
    assert "--repeats 0: must be >= 1" in capsys.readouterr().err


def test_startup_rows_are_measured_and_documented(tmp_path, capsys):
    """`bench --startup` on one FCC cell in its box (4 touching spheres, 6 pairs) from a CSV
    beside the two-sphere baseline: each row timed to the first step in a fresh process, its
    stages adding up to no more than the total, every key documented; bad options refused."""
    out = tmp_path / "startup.json"
    assert (
        main(["bench", "--startup", "--sizes", "1x1x1", "--formats", "csv", "--repeats", "1", "--json", str(out)]) == 0
    )
    rows = json.loads(out.read_text())
    text = (ROOT / "docs" / "benchmarks.md").read_text().split("### Start-up JSON")[1].split("\n## ")[0]
    documented = {
        k
        for line in text.splitlines()
        if line.startswith("| `")
        for k in re.findall(r"`([a-z_0-9]+)`", line.split("|")[1])
    }
    assert [(r["spheres"], r["format"], r["pairs"]) for r in rows] == [(2, "toml", 1), (4, "csv", 6)]
    for r in rows:
        assert set(r) <= documented, set(r) - documented
        stages = r["import_s"] + r["read_s"] + r["build_s"] + r["loop_start_s"]
        assert 0.0 < stages <= r["first_step_s"] + 1e-9 and r["peak_bytes"] > 1e7 and r["file_bytes"] > 0
    assert rows[1]["beyond_two_s"] == pytest.approx(rows[1]["first_step_s"] - rows[0]["first_step_s"])
    assert main(["bench", "--startup", "--formats", "xls"]) == 2
    assert "--formats item 'xls': allowed toml, csv, npz, nc" in capsys.readouterr().err


def test_pour_rows_are_measured_and_documented(tmp_path, capsys, monkeypatch):
    """`bench --pour` on 30 spheres, one thread: settled (kinetic and residual within the
    layout's criteria), every key documented; bad sizes are a user error."""
    from granplate.bench import pour

    monkeypatch.setattr(pour, "WARM_UP", 2)
    out = tmp_path / "pour.json"
    assert main(["bench", "--pour", "--sizes", "30", "--threads", "1", "--json", str(out)]) == 0
    report = json.loads(out.read_text())
    (r,) = report["rows"]
    assert r["spheres"] == 30 and r["threads"] == 1 and r["settled"] and r["steps"] > 0
    lay = pour.pour_scenario(30, 1).layout
    assert r["kinetic"] <= lay.settle_tolerance and r["residual"] <= lay.settle_residual
    text = (ROOT / "docs" / "benchmarks.md").read_text().split("### Pour JSON")[1]
    documented = {
        k
        for line in text.splitlines()
        if line.startswith("| `")
        for k in re.findall(r"`([a-z_0-9]+)`", line.split("|")[1])
    }
    assert set(r) <= documented and "`target_s`" in text and report["target_s"] == pour.TARGET_S
    assert main(["bench", "--pour", "--sizes", "ten"]) == 2
    assert "--sizes 'ten'" in capsys.readouterr().err

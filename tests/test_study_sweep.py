"""A sweep on a 2-worker Dask LocalCluster gives exactly the table of running the designs
one by one (gp.simulate + gp.summary); an interrupted sweep resumes, computing only the
missing designs, to the same table; a failing design is recorded with its message while
the others complete; the CLI runs the documented smallest study through --scheduler."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import granplate as gp
from granplate.cli import main
from granplate.study import parse_study, sweep
from granplate.study.design import design_key, read_record

DOCS = Path(__file__).resolve().parent.parent / "docs"
#: 10 loads x 5 friction coefficients = 50 designs of one plate, 2e-5 s each.
STUDY = {
    "base": "ptfe-r05",
    "set": {"time.t_end": 2e-5},
    "parameters": {"load.q0": {"range": [5e3, 5e4], "num": 10}, "contact.mu": [0.05, 0.099, 0.2, 0.3, 0.4]},
}
#: Summary entries that are not reproducible numbers of the design.
NOT_COMPARED = ("wall_time_s", "loop_time_s", "compile_time_s", "scenario", "units", "contact_pairs")


@pytest.fixture(scope="module")
def client():
    from distributed import Client, LocalCluster

    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    with Client(cluster) as c:
        yield c
    cluster.close()


def one_by_one(texts: list[str], tmp_path: Path) -> list[dict]:
    """gp.summary(gp.simulate(design)) of each design, in a fresh process whose BLAS runs
    one thread, as a Dask worker's does (a multi-threaded BLAS sums in another order: the
    stress may then differ in its last bit)."""
    (tmp_path / "designs.json").write_text(json.dumps(texts))
    code = (
        "import json, sys, granplate as gp\n"
        "texts = json.load(open(sys.argv[1]))\n"
        "print(json.dumps([gp.summary(gp.simulate(gp.loads(t), progress=False)) for t in texts]))\n"
    )
    env = {**os.environ, **{k: "1" for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")}}
    done = subprocess.run(
        [sys.executable, "-c", code, str(tmp_path / "designs.json")],
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(done.stdout)


def table(path) -> xr.Dataset:
    with xr.open_dataset(path) as ds:
        return ds.load()


def comparable(ds: xr.Dataset) -> xr.Dataset:
    return ds.drop_vars(["wall_time_s", "compile_time_s"], errors="ignore")


def test_sweep_equals_designs_run_one_by_one_and_resumes(client, tmp_path):
    study = parse_study(STUDY)
    assert len(study.designs) == 50
    # interrupted after 20 designs (limit), then rerun: only the 30 missing are computed
    first = sweep(study, tmp_path / "a", client=client, limit=20, progress=False)
    assert (first.n_done_before, first.n_computed) == (0, 20)
    part = table(tmp_path / "a" / "results.nc")
    assert list(part.status.values).count("not run") == 30
    second = sweep(study, tmp_path / "a", client=client, progress=False)
    assert (second.n_done_before, second.n_computed, second.n_failed, second.lost) == (20, 30, 0, [])
    third = sweep(study, tmp_path / "a", client=client, progress=False)
    assert third.n_computed == 0
    resumed = table(tmp_path / "a" / "results.nc")
    # an uninterrupted sweep gives the same table
    whole = sweep(study, tmp_path / "b", client=client, progress=False)
    assert whole.n_computed == 50
    xr.testing.assert_identical(comparable(resumed), comparable(table(tmp_path / "b" / "results.nc")))
    assert (tmp_path / "a" / "results.csv").read_text().count("\n") == 51
    # ... and the designs run one by one (gp.simulate, gp.summary) give exactly its numbers
    assert list(resumed.status.values) == ["ok"] * 50
    for i, s in enumerate(one_by_one([gp.dumps(study.scenario(i)) for i in range(50)], tmp_path)):
        assert resumed["load.q0"].values[i] == study.designs[i][0]
        assert resumed["contact.mu"].values[i] == study.designs[i][1]
        assert resumed.key.values[i] == design_key(gp.dumps(study.scenario(i)))
        for name, value in s.items():
            if name in NOT_COMPARED:
                continue
            got = resumed[name].values[i]
            assert np.isnan(got) if value is None else got == value, (i, name, got, value)
    assert resumed["max_von_mises"].attrs["units"] == "Pa"
    assert resumed["load.q0"].attrs["units"] == "N/m"


def test_failing_design_is_recorded_and_the_others_complete(client, tmp_path):
    study = parse_study({"base": "ptfe-r05", "set": {"time.t_end": 1e-5}, "parameters": {"load.q0": [1e4, -1.0, 2e4]}})
    report = sweep(study, tmp_path, client=client, full=True, progress=False)
    assert (report.n_computed, report.n_failed) == (3, 1)
    ds = table(tmp_path / "results.nc")
    assert ds.status.values[0] == ds.status.values[2] == "ok"
    assert ds.status.values[1].startswith("ScenarioError: scenario field 'load.q0' = -1.0: must be >= 0")
    assert np.isnan(ds.ep_max_fraction.values[1]) and ds.n_steps.values[0] > 0
    rec = read_record(tmp_path, ds.key.values[1])
    assert rec["status"] == ds.status.values[1] and rec["summary"] is None
    assert rec["changes"] == {"time.t_end": 1e-5, "load.q0": -1.0}
    # --full keeps each successful design's result beside its record
    full = gp.read(tmp_path / "designs" / f"{ds.key.values[0]}.nc")
    assert gp.summary(full)["e_shock"] == ds.e_shock.values[0]
    assert not (tmp_path / "designs" / f"{ds.key.values[1]}.nc").exists()
    # a failure is a result: a rerun does not compute it again
    assert sweep(study, tmp_path, client=client, full=True, progress=False).n_computed == 0
    csv_rows = (tmp_path / "results.csv").read_text().splitlines()
    assert csv_rows[0].startswith("design,load.q0,") and csv_rows[0].endswith(",status,key")
    assert json.loads(json.dumps(rec))["key"] == ds.key.values[1]


def test_cli_runs_the_smallest_study_on_an_existing_scheduler(client, tmp_path, capsys):
    out = tmp_path / "out"
    rc = main(
        [
            "sweep",
            str(DOCS / "studies" / "smallest.toml"),
            "--out",
            str(out),
            "--scheduler",
            client.scheduler.address,
            "-q",
        ]
    )
    assert rc == 0
    ds = table(out / "results.nc")
    assert ds.sizes["design"] == 9 and list(ds.status.values) == ["ok"] * 9
    assert list(ds["layout.R2_ratio"].values[:3]) == [0.5, 0.75, 1.0]
    assert "computed: 9" in capsys.readouterr().out
    assert len(list((out / "designs").glob("*.json"))) == 9


def test_cli_refuses_a_bad_study_before_running(tmp_path, capsys):
    (tmp_path / "s.toml").write_text('base = "ptfe-r05"\n[parameters]\n"load.q0" = []\n')
    assert main(["sweep", str(tmp_path / "s.toml"), "--out", str(tmp_path / "o")]) == 2
    assert "parameters.load.q0" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


# ------------------------------------------------------------------------- optimize

OPTIMIZE = {
    "base": "ptfe-r05",
    "set": {"time.t_end": 1e-5},
    "parameters": {"load.q0": {"range": [1e3, 5e4], "log": True}, "contact.mu": [0.05, 0.2]},
    "objectives": {"eg_max_fraction": "minimize", "dissipated_fraction": "maximize"},
}


def dominated(a: list[float], b: list[float]) -> bool:
    """Whether (minimize, maximize) values a are dominated by b."""
    no_worse = b[0] <= a[0] and b[1] >= a[1]
    return no_worse and (b[0] < a[0] or b[1] > a[1])


def test_optimize_resumes_from_its_database(client, tmp_path):
    import csv

    import optuna

    from granplate.study.optimize import open_study, optimize, parse_optimization

    opt = parse_optimization(OPTIMIZE)
    # a trial left running by a killed run: failed on the next run, its parameters run again
    stale = open_study(opt, tmp_path, seed=0).ask(opt.space)
    first = optimize(opt, tmp_path, 4, client=client, progress=False)
    assert (first.n_before, first.n_computed + first.n_reused, first.n_failed) == (0, 4, 0)
    second = optimize(opt, tmp_path, 6, client=client, progress=False)
    assert (second.n_before, second.n_computed + second.n_reused) == (4, 2)
    assert optimize(opt, tmp_path, 6, client=client, progress=False).n_computed == 0
    study = optuna.load_study(study_name="granplate", storage=f"sqlite:///{tmp_path / 'optuna.db'}")
    states = [t.state.name for t in study.trials]
    assert states.count("COMPLETE") == 6 and states.count("FAIL") == 1
    assert study.trials[stale.number].state.name == "FAIL"
    assert any(t.params == stale.params and t.state.name == "COMPLETE" for t in study.trials)
    # every design is recorded, and a trial's values are its record's metrics
    for t in study.trials:
        if t.state.name == "COMPLETE":
            rec = read_record(tmp_path, t.user_attrs["key"])
            assert t.values == [rec["summary"]["eg_max_fraction"], rec["summary"]["dissipated_fraction"]]
    # the Pareto front: no trial dominates a front member; every undominated trial is on it
    rows = list(csv.DictReader(open(tmp_path / "trials.csv")))
    front = {int(r["trial"]) for r in csv.DictReader(open(tmp_path / "pareto.csv"))}
    points = {
        int(r["trial"]): [float(r["eg_max_fraction"]), float(r["dissipated_fraction"])]
        for r in rows
        if r["state"] == "COMPLETE"
    }
    undominated = {n for n, p in points.items() if not any(dominated(p, q) for q in points.values())}
    assert front == undominated and front
    assert (tmp_path / "pareto.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_ctrl_c_keeps_finished_designs_and_a_rerun_computes_only_the_rest(client, tmp_path):
    # Ctrl-C in a terminal signals the whole process group: driver and local workers
    import signal
    import time

    study = tmp_path / "s.toml"
    study.write_text(
        'base = "ptfe-r05"\n[set]\n"time.t_end" = 2e-4\n[parameters]\n'
        '"load.q0" = {range = [5e3, 5e4], num = 10}\n"contact.mu" = [0.05, 0.1, 0.2]\n'
    )
    out = tmp_path / "out"
    p = subprocess.Popen(
        [sys.executable, "-m", "granplate.cli", "sweep", str(study), "--out", str(out), "--workers", "2", "-q"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    deadline = time.monotonic() + 120
    while len(list((out / "designs").glob("*.json"))) < 3 and time.monotonic() < deadline:
        time.sleep(0.05)
    os.killpg(p.pid, signal.SIGINT)
    _, err = p.communicate(timeout=60)
    assert p.returncode == 130, err
    assert "rerun the same command" in err and "Traceback" not in err
    kept = len(list((out / "designs").glob("*.json")))
    assert 3 <= kept < 30
    ds = table(out / "results.nc")
    assert list(ds.status.values).count("not run") == 30 - kept
    rerun = sweep(parse_study(tomllib.loads(study.read_text())), out, client=client, progress=False)
    assert (rerun.n_done_before, rerun.n_computed) == (kept, 30 - kept)
    assert list(table(out / "results.nc").status.values) == ["ok"] * 30


def test_a_killed_worker_loses_no_design(tmp_path):
    """SIGKILL of a worker process in the middle of a sweep: Dask runs its design again
    elsewhere (the nanny restarts the worker), nothing is lost, and the table equals that
    of an undisturbed sweep."""
    import signal
    import threading
    import time

    from distributed import Client, LocalCluster

    from granplate.results.engine import worker_pids

    study = parse_study(
        {"base": "ptfe-r05", "set": {"time.t_end": 1e-4}, "parameters": {"load.q0": {"range": [1e4, 5e4], "num": 12}}}
    )
    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    killed: list[int] = []
    with Client(cluster) as c:
        c.wait_for_workers(2)

        def kill_one_when_a_design_is_in() -> None:
            deadline = time.monotonic() + 120
            while not list((tmp_path / "a" / "designs").glob("*.json")) and time.monotonic() < deadline:
                time.sleep(0.01)
            pid = sorted(worker_pids(c).values())[0]
            os.kill(pid, signal.SIGKILL)
            killed.append(len(list((tmp_path / "a" / "designs").glob("*.json"))))

        killer = threading.Thread(target=kill_one_when_a_design_is_in)
        killer.start()
        report = sweep(study, tmp_path / "a", client=c, progress=False)
        killer.join()
        undisturbed = sweep(study, tmp_path / "b", client=c, progress=False)
    cluster.close()
    assert killed and 1 <= killed[0] < 12, "the worker was not killed during the sweep"
    assert (report.n_computed, report.n_failed, report.lost) == (12, 0, [])
    xr.testing.assert_identical(
        comparable(table(tmp_path / "a" / "results.nc")), comparable(table(tmp_path / "b" / "results.nc"))
    )
    assert undisturbed.n_computed == 12


def cli_sweep(client, tmp_path: Path, capsys, parameter: str) -> tuple[int, list[str]]:
    """`granplate sweep` (quiet, no report) of two 1e-5 s designs of ptfe-r05 varying one
    parameter (a TOML line of [parameters]) into tmp_path/o: (exit status, stderr lines)."""
    (tmp_path / "s.toml").write_text(f'base = "ptfe-r05"\n[set]\n"time.t_end" = 1e-5\n[parameters]\n{parameter}\n')
    rc = main(
        [
            "sweep",
            str(tmp_path / "s.toml"),
            "--out",
            str(tmp_path / "o"),
            "--scheduler",
            client.scheduler.address,
            "-q",
            "--no-report",
        ]
    )
    return rc, capsys.readouterr().err.strip().splitlines()


def test_cli_sweep_with_a_failing_design_exits_1_and_says_how_many(client, tmp_path, capsys):
    """Truth: of two designs one has a negative load (refused when it runs): the sweep
    exits 1 and its last line says 1 of 2 designs failed."""
    rc, err = cli_sweep(client, tmp_path, capsys, '"load.q0" = [1e4, -1.0]')
    assert rc == 1
    assert err[-1] == "granplate: 1 of 2 designs failed"


def test_cli_optimize_with_failing_trials_exits_1_and_labels_its_bar(client, tmp_path, capsys):
    """Truth: every trial's design has a negative load, so both trials fail: optimize exits
    1, its last line says 2 of 2 trials failed, and its progress bar reads "optimize"."""
    (tmp_path / "o.toml").write_text(
        'base = "ptfe-r05"\n[set]\n"time.t_end" = 1e-5\n'
        '[parameters]\n"load.q0" = [-1.0, -2.0]\n'
        '[objectives]\n"ep_max_fraction" = "minimize"\n'
    )
    rc = main(
        [
            "optimize",
            str(tmp_path / "o.toml"),
            "--out",
            str(tmp_path / "o"),
            "--trials",
            "2",
            "--scheduler",
            client.scheduler.address,
            "--no-report",
        ]
    )
    err = capsys.readouterr().err
    assert rc == 1
    assert err.strip().splitlines()[-1] == "granplate: 2 of 2 trials of this run failed"
    assert "optimize:" in err and "sweep:" not in err


def test_cli_sweep_says_how_many_designs_warned_and_keeps_their_warnings(client, tmp_path, capsys):
    """Truth: of two designs one warns (overlaps beyond a tiny contact.overlap_warn): the
    workers print nothing, the sweep's stderr says 1 of the 2 designs warned with that
    design's warning, its record lists it, and the other's record has none."""
    rc, err = cli_sweep(client, tmp_path, capsys, '"contact.overlap_warn" = [0.05, 1e-6]')
    assert rc == 0
    assert err[-1].startswith(
        "granplate: 1 of the 2 designs computed now warned (each record in designs/ "
        "lists its warnings); the first, design 1: RuntimeWarning: ptfe-r05: "
    )
    ds = table(tmp_path / "o" / "results.nc")
    records = [read_record(tmp_path / "o", k) for k in ds.key.values]
    assert records[0]["warnings"] == [] and len(records[1]["warnings"]) == 1

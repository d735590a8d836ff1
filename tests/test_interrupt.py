"""A run can be stopped: a stop request or SIGINT ends the compiled loop between chunks
(each bounded by a step budget of about CHUNK_SECONDS), and the result so far is kept."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

import granplate as gp
from granplate.errors import SimulationError
from granplate.results.run import interrupted, simulate
from granplate.solver import driver

ROOT = Path(__file__).resolve().parents[1]


def test_stop_request_ends_run_with_partial_record():
    """should_stop -> status INTERRUPTED after the first chunk, the rows so far kept."""
    model = gp.build_model(gp.with_changes(gp.preset("steel-r1"), {"time.t_end": 1e-4}))
    calls = []

    def stop():
        calls.append(1)
        return len(calls) > 1

    rec = driver.run(model, should_stop=stop, interruptible=False)
    assert rec.status == driver.INTERRUPTED
    assert rec.message.startswith(driver.INTERRUPTED_STATUS)
    assert 1 <= rec.n_valid < len(driver.output_times(1e-4, model.config.out_dt))


def test_signal_handlers_restored_after_a_run():
    """The SIGINT/SIGTERM handlers in place before a run are there again after it."""
    before = signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)
    with driver.stop_on_signals() as stopped:
        assert not stopped()
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(0.01)
        assert stopped()
    assert (signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)) == before


def test_step_budget_follows_wall_time_target():
    """A chunk of n steps that took s seconds gives a budget of CHUNK_SECONDS n / s."""
    assert driver.next_budget(64, 1000, 2 * driver.CHUNK_SECONDS) == 500
    assert driver.next_budget(64, 10, 1e3) == 1


def test_interrupted_simulate_raises_with_partial_dataset(monkeypatch):
    """simulate stopped by SIGINT: SimulationError whose .result has status 'interrupted'."""
    real = driver.next_budget

    def budget_then_signal(*args):  # after the first chunk, inside the run
        os.kill(os.getpid(), signal.SIGINT)
        return real(*args)

    monkeypatch.setattr(driver, "next_budget", budget_then_signal)
    s = gp.with_changes(gp.preset("steel-r1"), {"solver.scheme": "paper"})
    with pytest.raises(SimulationError) as err:
        simulate(s, t_end=1e-4, progress=False)
    assert interrupted(err.value.result)
    assert "interrupted by the user at t = " in str(err.value)


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_cli_ctrl_c_writes_partial_file(tmp_path):
    """`granplate run` of a long case gets SIGINT once it shows progress: it returns
    within a few seconds with code 130 and the result so far in the -o file."""
    out = tmp_path / "r.nc"
    scenario = tmp_path / "long.toml"
    gp.dump(gp.with_changes(gp.preset("steel-r1"), {"solver.scheme": "paper", "time.t_end": 1e-2}), scenario)
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.Popen(
        [sys.executable, "-m", "granplate.cli", "run", str(scenario), "-o", str(out)],
        stderr=subprocess.PIPE,
        stdout=subprocess.PIPE,
        env=env,
        cwd=tmp_path,
    )
    seen = b""
    deadline = time.monotonic() + 300  # a cold numba cache compiles first
    while time.monotonic() < deadline:
        chunk = os.read(proc.stderr.fileno(), 4096)
        if not chunk:
            break
        seen += chunk
        if re.search(rb"\s[1-9]\d*/\d+ \[", seen):  # the bar shows a finished output interval
            break
    assert proc.poll() is None, seen.decode(errors="replace")
    t0 = time.monotonic()
    proc.send_signal(signal.SIGINT)
    _, rest = proc.communicate(timeout=30)
    elapsed = time.monotonic() - t0
    text = (seen + rest).decode(errors="replace")
    assert proc.returncode == 130, text
    assert elapsed < 5.0, text
    assert "interrupted by the user" in text and str(out) in text
    ds = gp.read(out)
    assert interrupted(ds) and ds.sizes["time"] >= 2


def test_run_whose_clock_stops_ends_with_a_message(monkeypatch):
    """A loop that keeps pausing without moving the clock is stopped by the driver after
    STALL_ATTEMPTS attempts with the step-control message, the rows so far kept."""
    model = gp.build_model(gp.with_changes(gp.preset("steel-r1"), {"time.t_end": 1e-5}))
    calls = []

    def frozen(t_stop, budget, g, p, b, cfg, st, w, sw, out):
        calls.append(budget)
        st.count[driver.S.C_RETRIES] += 1
        return driver.S.PAUSED

    monkeypatch.setattr(driver.loop, "advance", frozen)
    rec = driver.run(model, interruptible=False)
    assert rec.status == driver.S.ERR_NOCONV
    assert "cannot move the clock on at t = 0.000000e+00 s" in rec.message
    assert len(calls) == driver.STALL_ATTEMPTS + 1 and rec.n_valid == 1


def test_signal_while_building_the_result_keeps_the_times_built(monkeypatch, tmp_path):
    """SIGINT while the plate's stresses are computed after the loop: SimulationError whose
    .result holds the output times built so far (one block), says 'interrupted by the user
    at t = ... while building the result', and writes to netCDF with its plate fields."""
    from granplate.plate import peaks

    real = peaks.block_maxima
    calls = []

    def signal_then_build(plate, c):
        if not calls:
            os.kill(os.getpid(), signal.SIGINT)
        calls.append(len(c))
        return real(plate, c)

    monkeypatch.setattr(peaks, "block_maxima", signal_then_build)
    with pytest.raises(SimulationError) as err:
        simulate(gp.preset("steel-r1"), t_end=1e-4, progress=False)
    ds = err.value.result
    assert interrupted(ds) and "while building the result" in ds.attrs["status"]
    assert ds.sizes["time"] == peaks.BLOCK == calls[0] and len(calls) == 1
    assert f"at t = {float(ds.time[-1]):.6e} s" in str(err.value)
    back = gp.read(gp.write(ds, tmp_path / "partial.nc"))
    assert back.sizes["time"] == peaks.BLOCK and "plate_ux" in back and back.sizes["field_time"] >= 1


def test_signal_while_writing_finishes_the_file(monkeypatch, tmp_path):
    """`granplate run` with SIGINT arriving while the result is written: the whole file is
    written (every output time) and the command exits with 130."""
    import xarray as xr

    from granplate import cli

    real = xr.Dataset.to_netcdf

    def signal_then_write(self, *args, **kwargs):
        os.kill(os.getpid(), signal.SIGINT)
        return real(self, *args, **kwargs)

    monkeypatch.setattr(xr.Dataset, "to_netcdf", signal_then_write)
    scenario, out = tmp_path / "short.toml", tmp_path / "short.nc"
    gp.dump(gp.with_changes(gp.preset("steel-r1"), {"time.t_end": 1e-4}), scenario)
    assert cli.main(["run", str(scenario), "-o", str(out), "--quiet"]) == 130
    monkeypatch.setattr(xr.Dataset, "to_netcdf", real)
    ds = gp.read(out)
    assert ds.sizes["time"] == 101 and not interrupted(ds)

"""Simulate a scenario and return the result Dataset.

>>> import granplate
>>> ds = granplate.simulate(granplate.preset("steel-r1"), t_end=1e-4)
"""

from __future__ import annotations

import json
import sys
import time
import warnings
from dataclasses import replace

from granplate.errors import SimulationError, YieldWarning
from granplate.model.arrays import Model, build_model
from granplate.results.restart import check_restart, restart_source, restart_state, with_restart
from granplate.results.dataset import to_dataset
from granplate.setup.scenario import Scenario
from granplate.solver.compiling import CompileClock, compile_clock
from granplate.solver.driver import INTERRUPTED_STATUS, run as run_loop, stop_on_signals
from granplate.solver.state import OK


def yield_note(ds) -> None:
    """Warn once (errors.YieldWarning) when elastic contacts of the result passed the onset of
    yield (results.yielding.yield_warning)."""
    from granplate.results.yielding import PairYield, yield_warning

    if "material_pair" not in ds.coords or ds.sizes["material_pair"] == 0:
        return
    py = PairYield(
        pair=tuple(str(v) for v in ds.material_pair.values),
        pressure=ds.pair_max_contact_pressure.values,
        ratio=ds.pair_yield_onset_ratio.values,
        yield_strength=ds.pair_yield_strength.values,
        time=ds.pair_max_pressure_time.values,
        contact=tuple(str(v) for v in ds.pair_max_pressure_contact.values),
        law=tuple(str(v) for v in ds.pair_normal_law.values),
    )
    line = yield_warning(ds.attrs.get("scenario_name", ""), py)
    if line is not None:
        warnings.warn(line, YieldWarning, stacklevel=3)


def interrupted(ds) -> bool:
    """Whether the result `ds` is that of a run stopped by the user (SIGINT/SIGTERM)."""
    return str(ds.attrs.get("status", "")).startswith(INTERRUPTED_STATUS)


def with_t_end(scenario: Scenario, t_end: float) -> Scenario:
    """The scenario with time.t_end = t_end [s] (the output interval cut to fit)."""
    scenario = replace(scenario, time=replace(scenario.time, t_end=float(t_end)))
    if scenario.time.output_interval > scenario.time.t_end:
        scenario = replace(scenario, time=replace(scenario.time, output_interval=scenario.time.t_end))
    return scenario


def simulate(
    scenario: Scenario,
    *,
    t_end: float | None = None,
    progress: bool | None = None,
    model: Model | None = None,
    summary_only: bool = False,
    compile_all: bool = False,
    start_from=None,
    start_time: float | None = None,
):
    """Simulate `scenario` and return an xarray Dataset (see docs/output.md).

    t_end overrides scenario.time.t_end [s]; progress shows a bar (default: when stderr
    is a terminal); model: the scenario's model when already built; summary_only: return
    only what `summary` reads (energies, plate maxima, residual, granule masses; the same
    numbers without the plate fields, for studies that keep only the summary);
    compile_all: when this run's time loop is not compiled yet, first compile every
    scheme's kernels in both dimensions (`results.kernels`: the command line's first run).
    The result's wall_time_s leaves out the seconds numba compiled, which it states as
    compile_time_s. Raises SimulationError (with the partial, whole Dataset in `.result`,
    its `status` attribute saying why) when the run goes numerically wrong or is stopped
    by SIGINT/SIGTERM (Ctrl-C). start_from: a result (Dataset) to restart from at its last
    output time, or at start_time [s], one of its stored restart times (time.restart_interval;
    docs/how-to/restart.md; absent: the scenario's [restart], if any): checked against the
    scenario (results.restart.check_restart) before anything runs.
    """
    if t_end is not None:
        scenario = with_t_end(scenario, t_end)
    start = None
    start_from, start_time, from_field, time_field = restart_source(scenario, start_from, start_time)
    if start_from is not None:
        t1 = check_restart(start_from, scenario, start_time, from_field, time_field)
        start = restart_state(start_from, t1)
    with compile_clock() as clock:
        if compile_all:
            from granplate.results.kernels import compile_kernels, needs_compiling

            if needs_compiling(scenario):
                compile_kernels()
        ds = _simulate(scenario, progress, model, summary_only, clock, start)
    if start_from is not None:  # the energies go on from the first run's t = 0 (docs/model.md section 7)
        ds.attrs["E_initial"] = start_from.attrs.get("E_initial", 0.0)
        ds.attrs["restarted_at"] = t1
    return ds


def _simulate(
    scenario: Scenario, progress: bool | None, model: Model | None, summary_only: bool, clock: CompileClock, start=None
):
    """simulate's run, its compile seconds counted by clock."""
    t0, c0 = time.perf_counter(), clock.now()
    if model is None:
        model = build_model(scenario)
    t_setup = time.perf_counter() - t0
    if progress is None:
        progress = sys.stderr.isatty()
    with stop_on_signals() as stop_requested:  # a signal after the loop stops building the result
        rec = run_loop(model, progress=progress, start=start)
        info = {
            "wall_time_s": time.perf_counter() - t0 - (clock.now() - c0),
            "compile_time_s": clock.now(),
            "setup_time_s": t_setup,
            **rec.info,
            "status": rec.message,
        }
        info = {
            k: info[k]
            for k in (
                "wall_time_s",
                "compile_time_s",
                "setup_time_s",
                "first_call_time_s",
                "loop_time_s",
                "loop_cpu_s",
                "loop_thread_cpu_s",
                "n_steps",
                "threads",
                "n_iterations",
                "n_retries",
                "n_friction_bound",
                "status",
            )
        }
        info["n_rebuilds"] = rec.contacts.n_rebuilds
        if rec.status == OK and summary_only:
            return _with_compile_time(
                to_dataset(model, rec.out, rec.n_valid, info, summary_only=True, contacts=rec.contacts), clock
            )
        ds = _with_compile_time(
            to_dataset(
                model, rec.out, rec.n_valid, info, contacts=rec.contacts, should_stop=stop_requested, progress=progress
            ),
            clock,
        )
        ds = with_restart(ds, rec.snapshot, rec.earlier)
    with_stride_note(ds, scenario, model)
    yield_note(ds)
    if rec.status != OK or interrupted(ds):
        n = ds.sizes["time"]
        t_last = float(ds.time[-1]) if n else 0.0
        raise SimulationError(
            f"{model.scenario.name}: {ds.attrs['status']} The {n} output times computed "
            f"so far (up to t = {t_last:.6e} s) are kept in the error's .result.",
            result=ds,
        )
    return ds


def with_stride_note(ds, scenario: Scenario, model: Model) -> None:
    """The attributes `output_stride` (k) and `output_interval_given` [s] of a run whose
    model outputs every k-th output time of `scenario` (setup.output_stride); none for k = 1."""
    given, run = scenario.time.output_interval, model.scenario.time.output_interval
    k = round(run / given)
    if k > 1:
        ds.attrs["output_stride"] = int(k)
        ds.attrs["output_interval_given"] = float(given)


def _with_compile_time(ds, clock: CompileClock):
    """ds with its compile_time_s (attribute and run_info) brought up to clock's seconds:
    what numba compiled while the Dataset was made counts too."""
    info = json.loads(ds.attrs.get("run_info", "{}"))
    info["compile_time_s"] = clock.now()
    ds.attrs["compile_time_s"] = info["compile_time_s"]
    ds.attrs["run_info"] = json.dumps(info)
    return ds

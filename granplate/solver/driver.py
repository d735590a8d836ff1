"""Run a scenario: build the model once, call the compiled loop in chunks (progress is
shown between chunks, never per step), and return the result Dataset.

    >>> import granplate
    >>> ds = granplate.simulate(granplate.preset("steel-r1"), t_end=1e-4)
"""
from __future__ import annotations

import math
import sys
import time
from dataclasses import replace

import numpy as np

from granplate.solver import kernels as K
from granplate.errors import SimulationError
from granplate.model.arrays import Model, build_model
from granplate.setup.scenario import Scenario


def _status_message(status: int, model: Model, st: K.State) -> str:
    e = st.err
    cfg = model.config
    t = e[K.ERR_T]
    if status == K.ERR_NOCONV:
        k = int(e[K.ERR_CONTACT])
        where = f"plate contact '{model.contact_labels[k]}'" if 0 <= k < len(model.contact_labels) else "the interface"
        return (
            f"the interface-force iteration cannot go on at t = {t:.6e} s: {where} has "
            f"|N| = {e[K.ERR_N]:.4g} N, slip rate {e[K.ERR_VT]:.4g} m/s, local-map modulus "
            f"|lambda| = {e[K.ERR_LAM]:.3g} (eq. 8) with step {e[K.ERR_H]:.3e} s after "
            f"{int(e[K.ERR_ITER])} iterations, and the step may not go below time.dt_min = "
            f"{cfg.dt_min:.3e} s. Lower solver.lambda_target, raise solver.max_iterations or "
            f"lower time.dt_min."
        )
    if status == K.ERR_ENERGY:
        return (
            f"energy balance broken at t = {t:.6e} s: residual (E_p + E_g + D - E_in)/E_in = "
            f"{e[K.ERR_RESID]:.3e} exceeds solver.energy_tol = {cfg.energy_tol:.1e} "
            f"(step {e[K.ERR_H]:.3e} s). Lower time.dt_max or solver.lambda_target."
        )
    if status == K.ERR_NAN:
        return f"the state became non-finite (NaN/inf) at t = {t:.6e} s (step {e[K.ERR_H]:.3e} s)."
    return f"output buffer exhausted at t = {t:.6e} s (internal error, status {status})."


def output_times(t_end: float, dt_out: float) -> np.ndarray:
    """Output times 0, dt_out, 2 dt_out, ..., ending exactly at t_end [s]."""
    n = int(math.ceil(t_end / dt_out - 1e-9))
    t = np.arange(n + 1) * dt_out
    t[-1] = t_end
    return t


def simulate(
    scenario: Scenario,
    *,
    t_end: float | None = None,
    progress: bool | None = None,
    model: Model | None = None,
):
    """Simulate `scenario` and return an xarray Dataset (see docs/output.md).

    t_end overrides scenario.time.t_end [s]; progress shows a bar (default: when stderr
    is a terminal). Raises SimulationError (with the partial Dataset in `.result`) when
    the run goes numerically wrong.
    """
    from granplate.results.dataset import to_dataset

    if t_end is not None:
        scenario = replace(scenario, time=replace(scenario.time, t_end=float(t_end)))
        if scenario.time.output_interval > scenario.time.t_end:
            scenario = replace(scenario, time=replace(scenario.time, output_interval=scenario.time.t_end))
    t0 = time.perf_counter()
    if model is None:
        model = build_model(scenario)
    t_setup = time.perf_counter() - t0
    g, p, cfg = model.granular, model.plate_arrays, model.config
    ng, nm, nk = model.n_granules, len(p.omega2), len(model.plate_contacts)
    times = output_times(cfg.t_end, cfg.out_dt)
    st = K.new_state(ng, nm, nk)
    w = K.new_work(ng, nm, nk, exact=cfg.scheme == K.SCHEME_IMPLICIT)
    out = K.new_output(times, ng, nm, nk)
    st.y[:] = model.initial_state
    st.count[K.C_LEVEL] = K.level_for(model.scenario.time.dt_initial, cfg)
    t1 = time.perf_counter()
    K.initialise(st, g, p, cfg, w)
    K.record(0, st, g, p, w, out)
    st.count[K.C_OUT] = 1
    t_first = time.perf_counter() - t1  # includes compiling / loading the kernels

    if progress is None:
        progress = sys.stderr.isatty()
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=len(times) - 1, desc=model.scenario.name, unit="out", leave=False)
    n_chunks = min(200, len(times) - 1)
    stops = np.unique(np.linspace(1, len(times) - 1, n_chunks).round().astype(int)) if n_chunks else []
    status = K.OK
    t2 = time.perf_counter()
    try:
        for o_stop in stops:
            before = st.count[K.C_OUT]
            status = K.advance(float(times[o_stop]), g, p, cfg, st, w, out)
            if bar is not None:
                bar.update(int(st.count[K.C_OUT] - before))
            if status != K.OK:
                break
    finally:
        if bar is not None:
            bar.close()
    t_loop = time.perf_counter() - t2
    n_valid = int(st.count[K.C_OUT])
    info = {
        "wall_time_s": time.perf_counter() - t0,
        "setup_time_s": t_setup,
        "first_call_time_s": t_first,
        "loop_time_s": t_loop,
        "n_steps": int(st.count[K.C_STEPS]),
        "n_iterations": int(st.count[K.C_ITERS]),
        "n_retries": int(st.count[K.C_RETRIES]),
        "status": "ok" if status == K.OK else _status_message(status, model, st),
    }
    ds = to_dataset(model, out, n_valid, info)
    if status != K.OK:
        raise SimulationError(
            f"{model.scenario.name}: {info['status']} The {n_valid} output times computed "
            f"so far (up to t = {times[n_valid - 1]:.6e} s) are kept in the error's .result.",
            result=ds,
        )
    return ds

"""Run the compiled loop on a model: allocate the state once, call `loop.advance` in
chunks (each bounded by output times and by a step budget calibrated to a wall-time
target, so progress shows and a stop request is honoured within about a second, even
when the steps have collapsed), and return a plain record of the output buffers.
"""
from __future__ import annotations

import math
import signal
import threading
import time
from contextlib import contextmanager
from typing import Callable, NamedTuple

import numpy as np

from granplate.model.arrays import Model
from granplate.solver import loop, state as S
from granplate.solver.ladder import level_for
from granplate.solver.schemes import scheme

#: wall-time target of one compiled chunk [s], and the step budget of the first one.
CHUNK_SECONDS = 0.15
FIRST_BUDGET = 64
#: status of a run stopped by a signal (SIGINT, SIGTERM) or a stop request.
INTERRUPTED = -1
INTERRUPTED_STATUS = "interrupted by the user"


class RunRecord(NamedTuple):
    """What the loop leaves: the output buffers, how many rows are valid, the status
    code (state.OK, an error code, or INTERRUPTED), its message ("ok" or why the run
    stopped) and the timings and counters (info)."""

    out: S.Output
    n_valid: int
    status: int
    message: str
    info: dict


def output_times(t_end: float, dt_out: float) -> np.ndarray:
    """Output times 0, dt_out, 2 dt_out, ..., ending exactly at t_end [s]."""
    n = int(math.ceil(t_end / dt_out - 1e-9))
    t = np.arange(n + 1) * dt_out
    t[-1] = t_end
    return t


def status_message(status: int, model: Model, st: S.State) -> str:
    """Why the run stopped, naming the quantities, the limits and what to change."""
    e = st.err
    cfg = model.config
    t = e[S.ERR_T]
    if status == INTERRUPTED:
        return f"{INTERRUPTED_STATUS} at t = {st.clock[S.T_NOW]:.6e} s."
    if status == S.ERR_NOCONV:
        k = int(e[S.ERR_CONTACT])
        where = f"plate contact '{model.contact_labels[k]}'" if 0 <= k < len(model.contact_labels) else "the interface"
        return (
            f"the interface-force iteration cannot go on at t = {t:.6e} s: {where} has "
            f"|N| = {e[S.ERR_N]:.4g} N, slip rate {e[S.ERR_VT]:.4g} m/s, local-map modulus "
            f"|lambda| = {e[S.ERR_LAM]:.3g} (eq. 8) with step {e[S.ERR_H]:.3e} s after "
            f"{int(e[S.ERR_ITER])} iterations, and the step may not go below time.dt_min = "
            f"{cfg.dt_min:.3e} s. Lower solver.lambda_target, raise solver.max_iterations or "
            f"lower time.dt_min."
        )
    if status == S.ERR_ENERGY:
        return (
            f"energy balance broken at t = {t:.6e} s: residual (E_p + E_g + D - E_in)/E_in = "
            f"{e[S.ERR_RESID]:.3e} exceeds solver.energy_tol = {cfg.energy_tol:.1e} "
            f"(step {e[S.ERR_H]:.3e} s). Lower time.dt_max or solver.lambda_target."
        )
    if status == S.ERR_NAN:
        return f"the state became non-finite (NaN/inf) at t = {t:.6e} s (step {e[S.ERR_H]:.3e} s)."
    return f"output buffer exhausted at t = {t:.6e} s (internal error, status {status})."


@contextmanager
def stop_on_signals():
    """Yield a function telling whether SIGINT or SIGTERM arrived meanwhile; the
    previous handlers are restored afterwards. Outside the main thread no handler is
    installed (signals cannot be caught there) and the function always says no."""
    flag = {"stop": False}
    if threading.current_thread() is not threading.main_thread():
        yield lambda: False
        return

    def handler(signum, frame):
        flag["stop"] = True

    old = {sig: signal.signal(sig, handler) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield lambda: flag["stop"]
    finally:
        for sig, h in old.items():
            signal.signal(sig, h)


def next_budget(budget: int, attempts: int, seconds: float) -> int:
    """Step budget of the next chunk so that it lasts about CHUNK_SECONDS."""
    if seconds <= 0.0 or attempts <= 0:
        return min(budget * 2, 1 << 24)
    per = seconds / attempts
    return int(min(max(CHUNK_SECONDS / per, 1), 1 << 24))


def _loop_chunks(times, model, st, w, sw, out, should_stop, on_progress) -> int:
    """Call the compiled loop chunk by chunk until the end, an error or a stop request."""
    g, p, cfg = model.granular, model.plate_arrays, model.config
    n_chunks = min(200, len(times) - 1)
    stops = np.unique(np.linspace(1, len(times) - 1, n_chunks).round().astype(int)) if n_chunks else []
    budget = FIRST_BUDGET
    for o_stop in stops:
        status = S.PAUSED
        while status == S.PAUSED:
            if should_stop():
                return INTERRUPTED
            before = st.count[S.C_OUT]
            n0 = st.count[S.C_STEPS] + st.count[S.C_RETRIES]
            t0 = time.perf_counter()
            status = loop.advance(float(times[o_stop]), budget, g, p, cfg, st, w, sw, out)
            budget = next_budget(budget, int(st.count[S.C_STEPS] + st.count[S.C_RETRIES] - n0),
                                 time.perf_counter() - t0)
            on_progress(int(st.count[S.C_OUT] - before))
        if status != S.OK:
            return status
    return S.OK


def run(model: Model, *, progress: bool = False, should_stop: Callable[[], bool] | None = None,
        interruptible: bool = True) -> RunRecord:
    """Run the time loop of `model` to its t_end.

    progress: a bar on stderr; should_stop: polled between chunks (a stop request);
    interruptible: SIGINT/SIGTERM stop the run between chunks (main thread only).
    """
    g, p, cfg = model.granular, model.plate_arrays, model.config
    ng, nm, nk = model.n_granules, len(p.omega2), len(model.plate_contacts)
    times = output_times(cfg.t_end, cfg.out_dt)
    st = S.new_state(ng, nm, nk)
    w = S.new_work(ng, nm, nk)
    sw = scheme(cfg.scheme).new_scratch(ng, nm, nk)
    out = S.new_output(times, ng, nm, nk)
    st.y[:] = model.initial_state
    st.count[S.C_LEVEL] = level_for(model.scenario.time.dt_initial, cfg)
    t1 = time.perf_counter()
    loop.initialise(st, g, p, cfg, w)
    loop.record(0, st, g, p, w, out)
    st.count[S.C_OUT] = 1
    t_first = time.perf_counter() - t1  # includes compiling / loading the loop
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=len(times) - 1, desc=model.scenario.name, unit="out", leave=False)
    polls = [should_stop] if should_stop is not None else []
    t2 = time.perf_counter()
    try:
        with (stop_on_signals() if interruptible else _never()) as signalled:
            status = _loop_chunks(times, model, st, w, sw, out, lambda: signalled() or any(f() for f in polls),
                                  bar.update if bar is not None else (lambda n: None))
    finally:
        if bar is not None:
            bar.close()
    info = {
        "first_call_time_s": t_first,
        "loop_time_s": time.perf_counter() - t2,
        "n_steps": int(st.count[S.C_STEPS]),
        "n_iterations": int(st.count[S.C_ITERS]),
        "n_retries": int(st.count[S.C_RETRIES]),
    }
    message = "ok" if status == S.OK else status_message(status, model, st)
    return RunRecord(out=out, n_valid=int(st.count[S.C_OUT]), status=status, message=message, info=info)


@contextmanager
def _never():
    yield lambda: False

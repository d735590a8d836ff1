"""Run the compiled loop on a model: allocate the state once, call `loop.advance` in
chunks (each bounded by output times and by a step budget calibrated to a wall-time
target, so progress shows and a stop request is honoured within about a second, even
when the steps have collapsed), and return a plain record of the output buffers. Its
pieces have modules of their own (schedule, run_contacts, loop_arrays, stop_messages),
whose public names are importable from here too.
"""

from __future__ import annotations

import logging
import signal
import threading
import time
import warnings
from contextlib import contextmanager
from typing import Callable, NamedTuple

import numpy as np

from granplate.model.arrays import Model
from granplate.model.dimension import of_number
from granplate.solver import loop, snapshot, state as S
from granplate.solver.compiling import compile_calls, compile_seconds, describe_seconds, machine_slowdown
from granplate.solver.ladder import level_for
from granplate.solver.loop_arrays import LoopArrays, add_patch_contacts, attach_patches, map_pages
from granplate.solver.loop_arrays import near_face as near_face
from granplate.solver.run_contacts import ContactChanges, ContactLists
from granplate.solver.run_contacts import ContactPeaks as ContactPeaks, contact_peaks as contact_peaks
from granplate.solver.run_contacts import wall_offsets_now as wall_offsets_now
from granplate.solver.schedule import SNAP_RTOL, output_times
from granplate.solver.schedule import sensor_setup as sensor_setup, sensor_times as sensor_times
from granplate.solver.stop_messages import INTERRUPTED, overlap_warnings, status_message
from granplate.solver.stop_messages import INTERRUPTED_STATUS as INTERRUPTED_STATUS
from granplate.solver.stop_messages import contact_message as contact_message, partner_name as partner_name
from granplate.setup.run_checks import restart_steps
from granplate.setup.sensor_checks import sensor_interval

#: wall-time target of one compiled chunk [s], and the step budget of the first one.
CHUNK_SECONDS = 0.15
FIRST_BUDGET = 64

log = logging.getLogger(__name__)
#: step attempts without the clock moving after which a run is stopped (every retry
#: goes one ladder level deeper, so a run that still advances never needs more)
STALL_ATTEMPTS = 2 * S.N_LEVELS


class RunRecord(NamedTuple):
    """What the loop leaves: the output buffers, how many rows are valid, the status
    code (state.OK, an error code, or INTERRUPTED), its message ("ok" or why the run
    stopped), the timings and counters (info), and how the contacts changed (contacts:
    the patch contacts formed, which extend the output's contact axis, and the list
    rebuilds)."""

    out: S.Output
    n_valid: int
    status: int
    message: str
    info: dict
    contacts: ContactChanges
    body: object = None  # the run's elastic body in space (model.inputs.BodyArrays, its last contact state) or None
    snapshot: dict | None = None  # the loop's state at the end (solver.snapshot.capture), for a restart
    earlier: tuple = ()  # its states at the earlier restart times (time.restart_interval), in time order


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


def set_reference(w: S.Work, st: S.State, dimension: int) -> None:
    """Keep the granules' centres (their first `dimension` state columns) as the contact
    list's reference (the contact watch measures how far each has moved since)."""
    w.yref[:, :dimension] = st.y[:, :dimension]


def _refresh(lists: ContactLists, st: S.State, w: S.Work) -> int:
    """Rebuild or check the contact lists at the current state: OK or ERR_MISSED (st.err filled)."""
    miss = lists.refresh(st.y)
    set_reference(w, st, lists.model.config.dimension)
    if miss is None:
        return S.OK
    st.err[S.ERR_T] = st.clock[S.T_NOW]
    st.err[S.ERR_CONTACT] = miss.i
    st.err[S.ERR_ITER] = miss.partner
    st.err[S.ERR_N] = miss.overlap
    return S.ERR_MISSED


#: A run whose step RK4's stability on the granule friction cuts (solver.granular_friction
#: = "rk4") on more than FRICTION_BOUND_SHARE of FRICTION_BOUND_MIN_STEPS or more steps
#: is told how to lift that bound.
FRICTION_BOUND_SHARE = 0.5
FRICTION_BOUND_MIN_STEPS = 5000
FRICTION_BOUND_HINT = (
    "{name}: friction at granule contacts, integrated inside RK4 (solver.granular_friction = "
    '"rk4", the presets\' setting), sets the step on most steps so far (t = {t:.4g} s): the run '
    'is slow for stability, not accuracy. solver.granular_friction = "split" integrates that '
    "friction exactly at any step, but its splitting error is outside the step control: check a "
    "result against a run with solver.implicit_dt_max halved (docs/model.md section 6.4)."
)


def friction_bound(count: np.ndarray) -> bool:
    """Whether granule friction inside RK4 has set most steps of a long enough run."""
    steps = int(count[S.C_STEPS])
    return steps >= FRICTION_BOUND_MIN_STEPS and count[S.C_FRICTION_BOUND] > FRICTION_BOUND_SHARE * steps


def stalled(st: S.State) -> int:
    """ERR_NOCONV for a run whose clock no longer moves (st.err filled: time, last step)."""
    st.err[:] = 0.0
    st.err[S.ERR_T] = st.clock[S.T_NOW]
    st.err[S.ERR_H] = st.clock[S.H_LAST]
    st.err[S.ERR_CONTACT] = -1.0
    return S.ERR_NOCONV


def restart_indices(n_times: int, first: int, every: int) -> np.ndarray:
    """The output rows (of n_times, the first being output time number `first` of the whole
    run) at which the loop's state is stored for a restart, every `every` output times
    (time.restart_interval; 0: none), the last row left out (its state is the run's end)."""
    if every <= 0:
        return np.zeros(0, np.int64)
    o = np.arange(1, n_times - 1, dtype=np.int64)
    return o[(first + o) % every == 0]


def chunk_stops(n_times: int, also: np.ndarray) -> np.ndarray:
    """The output rows the compiled chunks stop at: up to 200 spread over the run, and
    every row of `also` (where the loop's state is captured)."""
    n_chunks = min(200, n_times - 1)
    spread = np.linspace(1, n_times - 1, n_chunks).round().astype(np.int64) if n_chunks else np.zeros(0, np.int64)
    return np.union1d(spread, also).astype(np.int64)


def _loop_chunks(times, model, arr: LoopArrays, should_stop, on_progress, lists, captures=None, first=0) -> int:
    """Call the compiled loop chunk by chunk until the end, an error or a stop request;
    between chunks the contact lists are rebuilt when the loop asks (REBUILD), patch
    contacts added (NEW_PLATE) and, with fixed contacts, the lists checked after every
    chunk. captures: a list to which the loop's state (solver.snapshot.capture) is
    appended at every output time of `restart_indices` (times[0] being the run's output
    time number `first`). The lists are not made again at the end: fixed ones were checked
    after the last chunk, and dynamic ones hold every contact until a granule has moved
    half the skin, when the loop asks for a rebuild (REBUILD); the histories of every
    contact (ContactLists.changes) are those of the lists and of the stores either way."""
    cfg = model.config
    fixed = model.scenario.contact.detection == "fixed"
    keep = restart_indices(len(times), first, restart_steps(model.scenario.time)) if captures is not None else []
    stops = chunk_stops(len(times), np.asarray(keep, np.int64))
    budget = FIRST_BUDGET
    warned = False
    idle = 0  # step attempts since the clock last moved
    for o_stop in stops:
        status = S.PAUSED
        while status == S.PAUSED:
            if should_stop():
                return INTERRUPTED
            st = arr.st
            before = st.count[S.C_OUT]
            n0 = st.count[S.C_STEPS] + st.count[S.C_RETRIES]
            t_before = st.clock[S.T_NOW]
            t0 = time.perf_counter()
            status = loop.advance(float(times[o_stop]), budget, lists.g, arr.p, arr.b, cfg, st, arr.w, arr.sw, arr.out)
            attempts = int(st.count[S.C_STEPS] + st.count[S.C_RETRIES] - n0)
            budget = next_budget(budget, attempts, time.perf_counter() - t0)
            idle = idle + max(attempts, 1) if st.clock[S.T_NOW] <= t_before else 0
            if status == S.PAUSED and idle > STALL_ATTEMPTS:
                return stalled(st)
            on_progress(int(st.count[S.C_OUT] - before))
            if not warned and friction_bound(st.count):
                warned = True
                warnings.warn(
                    FRICTION_BOUND_HINT.format(name=model.scenario.name, t=st.clock[S.T_NOW]),
                    RuntimeWarning,
                    stacklevel=4,
                )
            if status in (S.REBUILD, S.NEW_PLATE) and cfg.face_skin > 0.0:
                add_patch_contacts(model, lists, arr)
            if status == S.REBUILD and not fixed:
                lists.n_rebuilds += 1
            if status == S.REBUILD or (fixed and status in (S.OK, S.PAUSED)):
                checked = _refresh(lists, arr.st, arr.w)
                if checked != S.OK:
                    return checked
            if status in (S.REBUILD, S.NEW_PLATE):
                status = S.PAUSED
        if status != S.OK:
            return status
        if o_stop in keep:
            captures.append(snapshot.capture(arr, lists))
    return S.OK


def type_fingerprint(a) -> tuple | type:
    """What numba's type of the argument `a` depends on, cheaply: a tuple's class and its
    members', an array's dtype, dimensions, layout and flags, else the Python type."""
    if isinstance(a, np.ndarray):
        f = a.flags
        return (np.ndarray, a.dtype.str, a.ndim, f.c_contiguous, f.f_contiguous, f.writeable, f.aligned)
    if isinstance(a, tuple):
        return (type(a), *(type_fingerprint(v) for v in a))
    return type(a)


#: (dispatcher id, argument fingerprints) already found compiled in this process.
_KNOWN_COMPILED: set[tuple] = set()


def is_compiled(dispatcher, args: tuple) -> bool:
    """Whether numba holds `dispatcher` compiled for these arguments' types, in memory or
    in its on-disk cache (an entry for this source and signature in the cache's index);
    True when numba's cache cannot be asked (then nothing is said about compiling). An
    answer True is kept for the arguments' fingerprint (typing them costs milliseconds)."""
    known = (id(dispatcher), tuple(type_fingerprint(a) for a in args))
    if known in _KNOWN_COMPILED:
        return True
    try:
        sig = tuple(dispatcher.typeof_pyval(a) for a in args)
        if sig in dispatcher.overloads:
            _KNOWN_COMPILED.add(known)
            return True
        cache = dispatcher._cache
        found = cache._index_key(sig, dispatcher.targetctx.codegen()) in cache._cache_file._load_index()
    except Exception:  # noqa: BLE001 - numba's cache internals: an unknown layout says nothing
        return True
    if found:
        _KNOWN_COMPILED.add(known)
    return found


def note_compile(model: Model, calls: list[tuple]) -> bool:
    """Log (INFO) that the time loop is about to be compiled, with the measured estimate,
    when any of `calls` ((dispatcher, args)) is not compiled yet; True when it is not."""
    if all(is_compiled(f, args) for f, args in calls):
        return False
    name, dim = model.scenario.solver.scheme, model.config.dimension
    where = of_number(dim).where
    seconds, slow = compile_seconds(name, dim), machine_slowdown()
    busy = f"; this machine is busy, {slow:.1f}x" if slow > 1.2 else ""
    log.info(
        f"compiling the time loop of the {name} scheme {where} (about {describe_seconds(slow * seconds)}: "
        f"{describe_seconds(seconds)} of CPU measured on a cold cache{busy}; cached afterwards) ..."
    )
    return True


def progress_bar(total: int, desc: str, file=None):
    """The run's progress bar over its output times, started once the loop is compiled:
    until the first output it shows no rate and no time left ("?"), never an estimate
    made from the compile time."""
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit="out", leave=False, file=file)


def run(
    model: Model,
    *,
    progress: bool = False,
    should_stop: Callable[[], bool] | None = None,
    interruptible: bool = True,
    start: dict | None = None,
) -> RunRecord:
    """Run the time loop of `model` to its t_end.

    progress: a bar on stderr; should_stop: polled between chunks (a stop request);
    interruptible: SIGINT/SIGTERM stop the run between chunks (main thread only);
    start: a restart (solver.snapshot.capture of a run of the same model ended at one of
    this run's output times t1): the loop goes on from there, its outputs from t1 on.
    """
    if start is not None:
        return _run_from(model, start, progress, should_stop, interruptible)
    g, cfg = model.granular, model.config
    times = output_times(cfg.t_end, cfg.out_dt)
    arr = LoopArrays(model, times, len(model.plate_contacts))
    st, w = arr.st, arr.w
    st.y[:] = model.initial_state
    if model.plate_q0 is not None:  # a precompressed plate starts deflected, at rest
        st.q[:] = model.plate_q0
        st.u[:] = model.plate_u0
    set_reference(w, st, cfg.dimension)
    w.plate_free[:] = 1
    w.plate_free[model.plate_contacts] = 0
    lists = ContactLists(model)
    if cfg.face_skin > 0.0:  # this run's own (patch contacts move their face)
        lists.g = lists.g._replace(pc_x=g.pc_x.copy())
        attach_patches(model, lists, arr, model.initial_patches)  # touching between nodes at t = 0
        st, w = arr.st, arr.w  # grown
    st.count[S.C_LEVEL] = level_for(model.scenario.time.dt_initial, cfg)
    map_pages(st, w, arr.sw, arr.b, arr.out, lists.g)  # (the pages the loop writes, mapped before its clock)
    calls = [
        (loop.initialise, (st, lists.g, arr.p, cfg, w)),
        (loop.start_scheme, (arr.sw, st, lists.g, arr.b, cfg)),
        (loop.record, (0, st, lists.g, arr.p, w, arr.out)),
        *sensor_calls(arr, st, lists.g, cfg),
        (loop.advance, (float(times[-1]), FIRST_BUDGET, lists.g, arr.p, arr.b, cfg, st, arr.w, arr.sw, arr.out)),
    ]
    t1 = time.perf_counter()
    note_compile(model, calls)
    compile_calls(calls)  # before the bar and the loop's clock: neither counts the compile
    loop.initialise(st, lists.g, arr.p, cfg, w)
    loop.start_scheme(arr.sw, st, lists.g, arr.b, cfg)
    loop.record(0, st, lists.g, arr.p, w, arr.out)
    first_sensor_sample(model, arr, st, lists.g)
    st.count[S.C_OUT] = 1
    return _finish(model, times, arr, lists, t1, progress, should_stop, interruptible)


def sensor_calls(arr: LoopArrays, st: S.State, g, cfg) -> list[tuple]:
    """The compiled call a run with sensors makes from Python (its first sample), to
    compile before the loop's clock starts; none without sensors."""
    return [(loop.record_sensors, (arr.sw, st, g, arr.b, cfg, arr.out))] if len(arr.out.sensor_granule) else []


def first_sensor_sample(model: Model, arr: LoopArrays, st: S.State, g) -> None:
    """The sensors' sample at the run's first output time, when it is a sample time (to
    SNAP_RTOL intervals: a restart's clock is the first run's end, to its rounding)."""
    if not len(arr.out.sensor_target):
        return
    if arr.out.sensor_target[0] <= st.clock[S.T_NOW] + SNAP_RTOL * sensor_interval(model.scenario):
        loop.record_sensors(arr.sw, st, g, arr.b, model.config, arr.out)


def _run_from(model: Model, start: dict, progress: bool, should_stop, interruptible: bool) -> RunRecord:
    """`run` from a captured state at an output time t1 (its clock): the outputs are the
    output times from t1 on, the first one the captured state itself."""
    cfg = model.config
    all_times = output_times(cfg.t_end, cfg.out_dt)
    t1 = float(start["st.clock"][S.T_NOW])
    o1 = int(np.argmin(np.abs(all_times - t1)))
    times = all_times[o1:]
    arr = LoopArrays(model, times, len(start["st.normal"]))
    lists = ContactLists(model)
    snapshot.restore(start, arr, lists)
    st = arr.st
    map_pages(st, arr.w, arr.sw, arr.b, arr.out, lists.g)
    calls = [
        (loop.record, (0, st, lists.g, arr.p, arr.w, arr.out)),
        *sensor_calls(arr, st, lists.g, cfg),
        (loop.advance, (float(times[-1]), FIRST_BUDGET, lists.g, arr.p, arr.b, cfg, st, arr.w, arr.sw, arr.out)),
    ]
    c1 = time.perf_counter()
    note_compile(model, calls)
    compile_calls(calls)
    loop.record(0, st, lists.g, arr.p, arr.w, arr.out)
    first_sensor_sample(model, arr, st, lists.g)
    st.count[S.C_OUT] = 1
    return _finish(model, times, arr, lists, c1, progress, should_stop, interruptible, first=o1)


def _finish(
    model: Model, times, arr: LoopArrays, lists: ContactLists, t1: float, progress, should_stop, interruptible, first=0
):
    """The loop from the first output on (its first call timed from t1 [perf_counter s];
    times[0] is the run's output time number `first`), and the run's record."""
    t_first = time.perf_counter() - t1  # includes compiling / loading the loop
    bar = None
    if progress:
        bar = progress_bar(len(times) - 1, model.scenario.name)
    polls = [should_stop] if should_stop is not None else []
    earlier: list[dict] = []
    t2 = time.perf_counter()
    c2, c3 = time.process_time(), time.thread_time()
    try:
        with stop_on_signals() if interruptible else _never() as signalled, numba_threads(model.config.threads):
            status = _loop_chunks(
                times,
                model,
                arr,
                lambda: signalled() or any(f() for f in polls),
                bar.update if bar is not None else (lambda n: None),
                lists,
                earlier,
                first,
            )
    finally:
        if bar is not None:
            bar.close()
    st, w = arr.st, arr.w
    info = {
        "first_call_time_s": t_first,
        "loop_time_s": time.perf_counter() - t2,
        "loop_cpu_s": time.process_time() - c2,
        "loop_thread_cpu_s": time.thread_time() - c3,
        "n_steps": int(st.count[S.C_STEPS]),
        "threads": int(model.config.threads),
        "n_iterations": int(st.count[S.C_ITERS]),
        "n_retries": int(st.count[S.C_RETRIES]),
        "n_friction_bound": int(st.count[S.C_FRICTION_BOUND]),
        "overlap_warnings": overlap_warnings(model, w),
    }
    message = "ok" if status == S.OK else status_message(status, model, st)
    body = arr.b if model.body is not None else None
    for line in info["overlap_warnings"]:
        warnings.warn(
            f"{model.scenario.name}: {line}: Hertz's law assumes overlaps small against the radii.",
            RuntimeWarning,
            stacklevel=2,
        )
    return RunRecord(
        out=arr.out,
        n_valid=int(st.count[S.C_OUT]),
        status=status,
        message=message,
        info=info,
        contacts=lists.changes(body),
        body=body,
        snapshot=snapshot.capture(arr, lists) if status == S.OK else None,
        earlier=tuple(earlier),
    )


@contextmanager
def numba_threads(n: int):
    """Numba's parallel loops on n threads inside the block (solver.blocks), the count
    before restored after it; 1: nothing changes (the serial loop starts no thread)."""
    if n <= 1:
        yield
        return
    import numba

    before = numba.get_num_threads()
    numba.set_num_threads(n)
    try:
        yield
    finally:
        numba.set_num_threads(before)


@contextmanager
def _never():
    yield lambda: False

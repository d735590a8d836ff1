"""What numba has compiled of the time loop, how long compiling it takes, and a clock of
the seconds spent compiling.

- `CompileClock` (`compile_clock()`): the seconds numba spends compiling while a block runs
  (its "numba:compile" events, the outermost only: a callee compiled inside its caller
  counts once; loading from numba's on-disk cache is no compile and is not counted), so
  that a run's wall time leaves them out and states them apart (`compile_time_s`).
- `compiled_loops()`: the (scheme, dimension, solid) keys whose time loop (`loop.advance`)
  numba holds compiled, in this process or in its on-disk cache, read from the cache's
  index without compiling or loading anything (solid: the loop with an elastic body's
  arrays, a type of its own, model.inputs.BodyArrays against NoBodyArrays).
- `compile_seconds(scheme, dimension)`: how long compiling a kernel set takes on a cold
  cache, measured (`compile_seconds.json`, written by `granplate compile --measure`).
- `compile_calls`: compile (or load) dispatchers for given arguments before a clock starts.
"""

from __future__ import annotations

import json
import os
from contextlib import contextmanager
from functools import lru_cache
from pathlib import Path
from typing import Iterator

#: Measured cold-cache compile times per kernel set (docs/benchmarks.md, "Compiling the kernels").
MEASURED_FILE = Path(__file__).with_name("compile_seconds.json")
#: A kernel set without a measurement: its estimate [s].
UNKNOWN_SECONDS = 60.0


class CompileClock:
    """Seconds numba spent compiling since the clock was installed (outermost compile
    events only; nested compiles belong to the one that triggered them)."""

    def __init__(self) -> None:
        self._depth = 0
        self._start = 0.0
        self.seconds = 0.0

    def on_start(self, event) -> None:
        import time

        if self._depth == 0:
            self._start = time.perf_counter()
        self._depth += 1

    def on_end(self, event) -> None:
        import time

        self._depth = max(self._depth - 1, 0)
        if self._depth == 0:
            self.seconds += time.perf_counter() - self._start

    def now(self) -> float:
        """The seconds so far, a compile in progress included up to now."""
        import time

        return self.seconds + (time.perf_counter() - self._start if self._depth else 0.0)


@contextmanager
def compile_clock() -> Iterator[CompileClock]:
    """A CompileClock counting the seconds numba compiles while the block runs."""
    from numba.core import event

    class _Listener(event.Listener):
        def on_start(self, ev):
            clock.on_start(ev)

        def on_end(self, ev):
            clock.on_end(ev)

    clock = CompileClock()
    with event.install_listener("numba:compile", _Listener()):
        yield clock


def loop_key(sig: tuple) -> tuple[str, int, bool] | None:
    """(scheme, dimension, solid) of a signature of `loop.advance` (its arguments t_stop,
    max_attempts, g, p, b, cfg, st, w, sw, out): the dimension from g's class (Granular or
    Granular3), the scheme from the module of sw's class (its Scratch), solid from the type
    of the body arrays b (carries_solid); None when unknown."""
    try:
        g, b, sw = sig[2], sig[4], sig[8]
        scheme = getattr(__import__(sw.instance_class.__module__, fromlist=["NAME"]), "NAME")
        from granplate.model.dimension import of_arrays

        dimension = of_arrays(g.instance_class).n
    except (AttributeError, IndexError, ImportError, TypeError, ValueError):
        return None
    return str(scheme), dimension, carries_solid(b)


def carries_solid(body_type) -> bool:
    """Whether the loop's body arrays (their numba type) are an elastic body's
    (model.inputs.BodyArrays; NoBodyArrays is a run without)."""
    from granplate.model.inputs import BodyArrays

    return getattr(body_type, "instance_class", None) is BodyArrays


def compiled_loops() -> set[tuple[str, int, bool]]:
    """The (scheme, dimension, solid) keys whose time loop numba holds compiled: in this process
    or in its on-disk cache's index for this source and this machine's code generator
    (read, not loaded: nothing is compiled). Empty when the cache cannot be read."""
    from granplate.solver import loop

    disp = loop.advance
    sigs = list(disp.overloads)
    try:
        magic = disp.targetctx.codegen().magic_tuple()
        index = disp._cache._cache_file._load_index()
        sigs += [key[0] for key in index if key[1] == magic]
    except Exception:  # noqa: BLE001 - numba's cache internals: an unknown layout says nothing is cached
        pass
    return {k for k in (loop_key(tuple(s)) for s in sigs) if k is not None}


def compile_calls(calls: list[tuple]) -> None:
    """Compile, or load from numba's cache, each (dispatcher, args) for these arguments'
    types, without running it (so that a clock started afterwards measures the run alone);
    a plain Python function in their place (a test's stand-in) is left alone."""
    for dispatcher, args in calls:
        if hasattr(dispatcher, "compile") and hasattr(dispatcher, "typeof_pyval"):
            dispatcher.compile(tuple(dispatcher.typeof_pyval(a) for a in args))


@lru_cache(maxsize=1)
def measured() -> dict:
    """The measurement of compile_seconds.json: {"seconds": {"SCHEME-Dd": s}, "machine": ...,
    "order": [...]}; empty where the file is absent."""
    try:
        return json.loads(MEASURED_FILE.read_text())
    except (OSError, ValueError):
        return {}


def machine_slowdown() -> float:
    """How many times longer than its CPU seconds a single-threaded compile takes here now:
    (the load average + 1, this process) over the cores it may use, at least 1 (an idle
    machine) and at most 10; 1 where the system does not say. A rough guess (measured:
    4.7x on 2 cores at load 5 to 8, set by set 3x to 9x); the estimates are corrected by
    the compile itself after the first kernel set."""
    try:
        cores = len(os.sched_getaffinity(0))
        load = os.getloadavg()[0]
    except (AttributeError, OSError):
        return 1.0
    return min(max(1.0, (load + 1.0) / max(cores, 1)), 10.0)


def set_name(scheme: str, dimension: int) -> str:
    """The kernel set's name in compile_seconds.json: "implicit-2d"."""
    return f"{scheme}-{dimension}d"


def compile_seconds(scheme: str, dimension: int) -> float:
    """Measured CPU seconds to compile a kernel set on a cold cache, after the sets before
    it in the measured order (they share callees); UNKNOWN_SECONDS without a measurement.
    On an idle core the wall time; `machine_slowdown` scales it to this machine now."""
    return float(measured().get("seconds", {}).get(set_name(scheme, dimension), UNKNOWN_SECONDS))


def describe_seconds(seconds: float) -> str:
    """'45 s' or '4 min 10 s': a duration a reader takes in at a glance."""
    s = int(round(seconds))
    return f"{s} s" if s < 120 else f"{s // 60} min {s % 60:02d} s"

"""How many cores a run's time loop uses (`solver.threads`, docs/model.md section 6.6).

The velocity-Verlet loop cuts its contacts and granules into one block per thread
(solver.blocks). Threads cost a few microseconds per parallel pass and step, which a small
assembly's whole step does not cover, so a scenario that does not say `solver.threads`
runs on every core only from PARALLEL_MIN_GRANULES granules on; the other schemes run
serially. The machine's cores are numba's thread count (the environment variable
NUMBA_NUM_THREADS lowers it; a design study's workers run one thread each). Where several
processes share the cores (a test suite's workers, a user's own pool of runs), the
environment variable GRANPLATE_THREADS sets what an absent `solver.threads` means (e.g. 1):
threads that wait for a core another process holds make every pass slow.
"""

from __future__ import annotations

import numbers
import os
from typing import Any

from granplate.errors import ScenarioError

#: An assembly of at least this many granules runs on every core when solver.threads is
#: absent (below it one thread is faster: docs/benchmarks.md, "Every core in one run").
PARALLEL_MIN_GRANULES = 2000
#: The schemes whose loop runs in blocks on several threads.
THREADED_SCHEMES: tuple[str, ...] = ("verlet",)


def available_threads() -> int:
    """The threads numba may run on this machine (its cores, or NUMBA_NUM_THREADS)."""
    import numba

    return int(numba.config.NUMBA_NUM_THREADS)


def check_threads(v: Any) -> None:
    """solver.threads: absent, or an integer from 1 to the machine's threads."""
    if v is None:
        return
    n = available_threads()
    if not isinstance(v, numbers.Integral) or isinstance(v, bool) or not 1 <= v <= n:
        raise ScenarioError(
            "solver.threads",
            v,
            f"must be an integer from 1 to {n} (the cores numba may use here: NUMBA_NUM_THREADS; a "
            f"design study's workers have one each), or absent (every core for {PARALLEL_MIN_GRANULES} "
            "granules and more)",
        )


def default_threads() -> int:
    """What an absent `solver.threads` means from PARALLEL_MIN_GRANULES granules on: the
    environment variable GRANPLATE_THREADS (an integer >= 1, at most the machine's
    threads), else every core."""
    text = os.environ.get("GRANPLATE_THREADS", "").strip()
    n = available_threads()
    if not text:
        return n
    if not text.isdigit() or int(text) < 1:
        raise ScenarioError("GRANPLATE_THREADS", text, f"must be an integer from 1 to {n} (unset: every core)")
    return min(int(text), n)


def loop_threads(requested: int | None, n_granules: int, scheme: str) -> int:
    """The threads the loop runs on: `requested` for a threaded scheme (absent:
    `default_threads()` from PARALLEL_MIN_GRANULES granules on, else 1); 1 for the other
    schemes."""
    if scheme not in THREADED_SCHEMES:
        return 1
    if requested is None:
        return default_threads() if n_granules >= PARALLEL_MIN_GRANULES else 1
    return int(requested)

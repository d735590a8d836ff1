"""The distributed engine: many independent simulations as tasks of a Dask cluster.

`granplate sweep`, `granplate optimize`, `granplate reproduce` and the long runs of
`granplate verify --full` all run here (docs/studies.md, "How the work is spread"):

- `dask_client`: a LocalCluster of worker processes with one thread (and one BLAS
  thread) each on this machine's cores, or an existing cluster by its scheduler's
  address (more machines: start workers there, nothing else changes);
- `warm_workers`: a short run on one worker first, then on all the others, so the numba
  kernels are compiled into numba's on-disk cache once and then only loaded (numba writes
  its cache files atomically, so concurrent writers are safe, but each would compile), and
  the first plate model is built once into the run store, where every worker finds it;
- `warm_up`: that short run (a task: a pure function of scenario TOML texts).

Tasks are pure functions of plain data (a scenario's TOML text in, a summary or a file
path out); callers gather them with `distributed.as_completed` and write each result as
it arrives, so an interruption loses only the tasks in flight.
"""

from __future__ import annotations

import logging
import os
import signal
import threading
import time
from contextlib import contextmanager
from typing import Iterable, Iterator

#: Simulated time of a worker's warm-up run [s] (compiles or loads the kernels, builds the plate).
WARM_T_END = 1e-6


def available_cores() -> int:
    """The cores this process may run on (its CPU affinity where the system tells it)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


@contextmanager
def sigint_ignored() -> Iterator[None]:
    """Ignore SIGINT (Ctrl-C) while processes are started (they keep ignoring it), then
    restore the handler; a no-op outside the main thread."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def numba_threads_from_environment() -> None:
    """numba's configuration read again from the environment (its thread count,
    NUMBA_NUM_THREADS), where its threads have not started. A Dask worker's environment
    (LocalCluster's `env`) is set after the worker process imported numba, whose thread
    count then stays the machine's until its next compile reads the environment again, and
    that compile fails ("Cannot set NUMBA_NUM_THREADS to a different value once the
    threads have been launched") where anything started the threads with the old count."""
    import numba

    try:
        numba.config.reload_config()
    except RuntimeError:  # the threads run already: the next compile reports it, naming the variable
        pass


def _numba_threads_plugin():
    """A Dask worker plugin that runs `numba_threads_from_environment` on every worker as
    it starts (and on each worker a nanny restarts)."""
    from distributed import WorkerPlugin

    class NumbaThreads(WorkerPlugin):
        name = "granplate-numba-threads"

        def setup(self, worker) -> None:
            numba_threads_from_environment()

    return NumbaThreads()


@contextmanager
def dask_client(workers: int | None = None, scheduler: str | None = None) -> Iterator:
    """A Dask Client: of the cluster at scheduler's address, else of a new LocalCluster of
    `workers` processes (default: the cores this process may use), one thread each; closed
    on exit. Local workers ignore Ctrl-C (it reaches the driver alone) and run numba's
    parallel loops on one thread (NUMBA_NUM_THREADS = 1: `solver.threads` absent means one
    there), so that workers and threads do not share the same cores."""
    from distributed import Client, LocalCluster

    if scheduler:
        client = Client(scheduler)
        try:
            yield client
        finally:
            client.close()
        return
    n = workers or available_cores()
    # silence_logs: Dask's own log lines stay out of the terminal, up to its errors: a
    # worker whose scheduler closed first (Ctrl-C, the end of a sweep) logs its failed
    # heartbeat as an error with a traceback; a design's own failure is its record's status,
    # and a task that does not come back is reported as lost by the sweep.
    with sigint_ignored():
        cluster = LocalCluster(
            n_workers=n,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
            silence_logs=logging.CRITICAL,
            env={"NUMBA_NUM_THREADS": "1"},
        )
    try:
        with Client(cluster) as client:
            client.register_plugin(_numba_threads_plugin())
            yield client
    finally:
        cluster.close()


def warm_up(scenario_tomls: Iterable[str]) -> float:
    """A short run (WARM_T_END) of each scenario, on a worker before its real tasks: the
    compiled kernels are loaded from numba's on-disk cache (or compiled and written there)
    and each plate model is built into, or read from, the run store. The seconds it took."""
    from granplate.results.run import simulate
    from granplate.setup.io import loads

    t0 = time.perf_counter()
    for text in scenario_tomls:
        s = loads(text)
        try:
            simulate(s, t_end=min(s.time.t_end, WARM_T_END), progress=False)
        except Exception:  # noqa: BLE001 - the task itself reports its failure later
            pass
    return time.perf_counter() - t0


def warm_workers(client, scenario_tomls: list[str]) -> float:
    """Run `warm_up(scenario_tomls)` on one worker, then on all the others at once (give
    one scenario per kernel variant: scheme, plate or not); the seconds."""
    t0 = time.perf_counter()
    client.wait_for_workers(1)
    workers = sorted(client.scheduler_info(n_workers=-1)["workers"])
    first, rest = workers[:1], workers[1:]
    for group in (first, rest):
        # asked of its worker, not bound to it: a worker lost while warming up must not
        # leave a task that waits for it forever
        futures = [
            client.submit(warm_up, list(scenario_tomls), workers=[w], allow_other_workers=True, pure=False)
            for w in group
        ]
        client.gather(futures, errors="skip")
        for f in futures:
            f.release()
    return time.perf_counter() - t0


def cancel(client, futures) -> None:
    """Cancel the tasks not finished; a cluster already gone (a lost scheduler) has
    nothing left to cancel."""
    if futures:
        try:
            client.cancel(list(futures))
        except Exception:  # noqa: BLE001 - no scheduler to tell
            pass


def worker_pids(client) -> dict[str, int]:
    """{worker address: process id} of the cluster's workers."""
    return client.run(os.getpid)

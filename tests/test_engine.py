"""The distributed engine's workers (results/engine.py): numba's thread count agrees with
the worker's environment before its threads start."""

from __future__ import annotations

import subprocess
import sys

#: a worker's life in one process: numba imported before the environment names one thread
#: (a Dask worker's `env` is set after its process imported granplate's command line), the
#: threads started, then a compile (which reads the environment again)
WORKER = """
import os, numba
os.environ["NUMBA_NUM_THREADS"] = "1"
{align}
numba.get_num_threads()
f = numba.njit(lambda x: x + 1)
print(f(1), numba.config.NUMBA_NUM_THREADS)
"""


def _run(align: str) -> subprocess.CompletedProcess:
    env = {"PATH": "/usr/bin:/bin", "NUMBA_NUM_THREADS": "2", "NUMBA_DISABLE_JIT": "0"}
    code = WORKER.format(align=align)
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=300)


def test_worker_compiles_after_its_threads_started():
    """With the engine's alignment, a compile after the threads started succeeds and numba
    counts the environment's one thread; without it numba refuses, as `granplate reproduce`'s
    workers did."""
    done = _run("from granplate.results.engine import numba_threads_from_environment\nnumba_threads_from_environment()")
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["2", "1"]
    refused = _run("")
    assert refused.returncode != 0
    assert "Cannot set NUMBA_NUM_THREADS" in refused.stderr

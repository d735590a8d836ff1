"""granplate.jit: kernels compile without numba's Python and C wrappers, give the same
numbers called from Python as from compiled code, and a run calls none from Python."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba.core.registry import CPUDispatcher

from granplate import jit
from granplate.jit import Kernel, njit


@njit
def _spring_energy(k: float, x: np.ndarray) -> float:
    e = 0.0
    for xi in x:
        e += 0.5 * k * xi * xi
    return e


@njit
def _total_energy(k: float, x: np.ndarray) -> float:
    return _spring_energy(k, x) + 1.0


@njit(entry=True)
def _entry_energy(k: float, x: np.ndarray) -> float:
    return _spring_energy(k, x)


def _has_python_wrapper(dispatcher) -> bool:
    """Whether the machine code numba built for the dispatcher's first signature holds the
    wrapper Python calls (named in the compile's function descriptor)."""
    compiled = next(iter(dispatcher.overloads.values()))
    return compiled.fndesc.llvm_cpython_wrapper_name in compiled.library.get_llvm_str()


def test_kernel_compiles_without_wrappers_and_python_gets_an_entry():
    """Called from compiled code, a kernel's machine code has no Python wrapper; called from Python it runs its entry, a separate dispatcher with the
    wrappers, with the closed form's value 1/2 k sum x^2."""
    x = np.array([1.0, -2.0, 0.5])
    assert _total_energy(3.0, x) == 0.5 * 3.0 * (1 + 4 + 0.25) + 1.0
    assert isinstance(_spring_energy, Kernel)
    assert not _has_python_wrapper(_spring_energy)
    assert _spring_energy._entry is None  # not called from Python yet
    assert _spring_energy(3.0, x) == 0.5 * 3.0 * (1 + 4 + 0.25)
    entry = _spring_energy.python_entry()
    assert entry is not _spring_energy and not isinstance(entry, Kernel)
    assert entry.py_func.__qualname__.endswith(jit.ENTRY_SUFFIX)
    assert any(n.endswith("test_jit._spring_energy") for n in jit.PYTHON_CALLS)


def test_entry_functions_are_numbas_own():
    """njit(entry=True) is numba's njit: a plain dispatcher compiled with its wrappers."""
    x = np.array([2.0])
    assert _entry_energy(1.0, x) == 2.0
    assert type(_entry_energy) is CPUDispatcher
    assert _has_python_wrapper(_entry_energy)


def test_a_run_calls_no_kernel_from_python():
    """Each kernel set's short runs (every scheme, both dimensions, with and without the
    solid) call only entry functions from Python: a kernel called from Python would compile
    its body twice; jit.PYTHON_CALLS counts every such call, also of a kernel whose entry
    an earlier test compiled)."""
    from granplate.results import kernels
    from granplate.results.run import simulate

    before = jit.PYTHON_CALLS.copy()
    for k in kernels.KERNEL_SETS:
        for s in k.scenarios():
            simulate(s, t_end=kernels.SHORT_T_END, progress=False)
    assert jit.PYTHON_CALLS - before == {}


class _Springs(NamedTuple):
    """A named tuple of arrays, as the loop's: positions and stiffnesses."""

    x: np.ndarray
    k: np.ndarray


def _springs(name: str, refcount: bool = False):
    """A kernel (its name) summing 1/2 k x^2 over the springs of positive k, each term by a
    kernel of its own: the shape of the loop's passes, whose reference counts numba keeps
    where a kernel counts them (`refcount`)."""

    def term(t: _Springs, i: int) -> float:
        return 0.5 * t.k[i] * t.x[i] * t.x[i]

    compiled_term = njit(term, refcount=refcount)

    def energy(t: _Springs) -> float:
        e = 0.0
        for i in range(t.x.shape[0]):
            if t.k[i] > 0.0:
                e += compiled_term(t, i)
        return e

    energy.__qualname__ = energy.__name__ = name
    return njit(energy, refcount=refcount)


#: the same kernel three times: one first called from a loop compiled with NO_REFCOUNT, one
#: from a plain function (numba's default: counting), and one that asks to count (refcount=True)
_energy_uncounted = _springs("_energy_uncounted")
_energy_plain_first = _springs("_energy_plain_first")
_energy_counted = _springs("_energy_counted", refcount=True)


def _repeated(kernel, **options):
    """An entry (compiled with `options`) summing kernel(t) over n calls: the shape of the
    time loop calling a kernel at every step."""

    def loop(t, n: int) -> float:
        s = 0.0
        for _ in range(n):
            s += kernel(t)
        return s

    return njit(loop, entry=True, **options)


_loop_uncounted = _repeated(_energy_uncounted, **jit.NO_REFCOUNT)
_loop_plain = _repeated(_energy_plain_first)
_loop_counted = _repeated(_energy_counted)


@njit(refcount=True)
def _ones(n: int) -> np.ndarray:
    return np.ones(n)


@njit(entry=True)
def _sum_of_ones(n: int) -> float:
    return _ones(n).sum()


def _counts_references(dispatcher) -> bool:
    """Whether the machine code numba built for the dispatcher calls its reference counting."""
    code = next(iter(dispatcher.overloads.values())).library.get_llvm_str()
    return "@NRT_incref" in code or "@NRT_decref" in code


def test_a_kernel_counts_no_references_whoever_calls_it_first():
    """A kernel is compiled as the time loop needs it (NO_REFCOUNT) whoever compiles it
    first: called first from a plain function (numba would have it inherit that function's
    counting, and keep it in its cache for the loop), it counts no references of the named
    tuple's arrays, like the same kernel the loop calls; one made with refcount=True counts
    them whoever calls it (so the check sees counting where there is some). All give
    1/2 k x^2 n."""
    t = _Springs(np.array([1.0, 2.0]), np.array([2.0, 0.5]))
    expected = 3 * (0.5 * 2.0 * 1.0 + 0.5 * 0.5 * 4.0)
    assert _loop_plain(t, 3) == _loop_uncounted(t, 3) == _loop_counted(t, 3) == expected
    assert _counts_references(_loop_plain)  # (the plain caller itself counts)
    assert not _counts_references(_energy_plain_first)
    assert not _counts_references(_loop_uncounted) and not _counts_references(_energy_uncounted)
    assert _counts_references(_energy_counted)
    assert _energy_plain_first.targetoptions["_nrt"] is False
    assert _energy_counted.targetoptions["_nrt"] is True


@njit(refcount=True)
def _ones_sum(n: int) -> float:
    return _ones(n).sum()


_loop_sum_of_ones = _repeated(_ones_sum, **jit.NO_REFCOUNT)


def test_a_kernel_that_makes_arrays_says_so_and_the_loop_may_call_it():
    """A kernel that allocates (np.ones) compiles with refcount=True, gives its arrays to a
    caller that counts, and frees them when a loop without counting calls it: the sum of n
    ones is n, and 1,000 calls leave numba's allocations balanced."""
    from numba.core.runtime import _nrt_python as nrt, rtsys

    assert _sum_of_ones(4) == 4.0
    _loop_sum_of_ones(3, 1)
    was_on = nrt.memsys_stats_enabled()
    nrt.memsys_enable_stats()
    try:
        before = rtsys.get_allocation_stats()
        assert _loop_sum_of_ones(3, 1000) == 3000.0
        after = rtsys.get_allocation_stats()
    finally:
        if not was_on:
            nrt.memsys_disable_stats()
    assert after.alloc - before.alloc == 1000
    assert after.alloc - before.alloc == after.free - before.free


def test_the_time_loop_counts_no_references_and_a_run_leaves_none_behind():
    """solver.loop.advance is compiled with NO_REFCOUNT, and a run (velocity Verlet, the
    plane) leaves the model's arrays with no more references than they had before it."""
    import gc
    import sys

    from granplate.model.arrays import build_model
    from granplate.results import kernels
    from granplate.solver import loop
    from granplate.solver.driver import run

    assert loop.advance.targetoptions.get("_nrt") is False
    s = next(k for k in kernels.KERNEL_SETS if k.name == "verlet-2d").scenarios()[0]
    m = build_model(s)
    arrays = [a for a in m.granular if isinstance(a, np.ndarray)]
    gc.collect()  # garbage left by earlier tests may still hold a cached array: free it first
    before = [sys.getrefcount(a) for a in arrays]
    run(m)
    gc.collect()
    after = [sys.getrefcount(a) for a in arrays]
    # none gains a reference (a set-up cache the run trims may drop one it held)
    assert all(a <= b for a, b in zip(after, before, strict=True)), (before, after)

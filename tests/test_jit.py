"""granplate.jit: kernels compile without numba's Python and C wrappers, give the same
numbers called from Python as from compiled code, and a run calls none from Python."""

from __future__ import annotations

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

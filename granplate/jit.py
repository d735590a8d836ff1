"""numba's `njit` as granplate's compiled code uses it: each kernel without the wrappers
that only a call from Python (or from C) needs.

numba builds two wrappers around every function it compiles, one that Python calls
(unboxing each argument: for a named tuple of 40 arrays, hundreds of lines of machine
code) and one that C calls. A kernel called only from other compiled code never uses
them, yet they were a third of the time its compile took (the plane's velocity-Verlet
loop from an empty cache: 184 s with them, 112 s without). So `njit` here compiles
without them, and a kernel that Python calls after all (a test, an interactive session)
compiles its own entry once, the same function with both wrappers, cached apart.

`njit(entry=True)` marks the functions the driver calls from Python (the time loop, its
start, the model build's kernels): compiled as numba compiles them, wrappers and all.

The time loop (`solver.loop.advance`) is compiled with `NO_REFCOUNT`: without numba's
reference counting, which every kernel it calls inherits (numba passes that option down to
the kernels a function calls when they do not set it). The loop hands the run's named
tuples of arrays (some 200 arrays) to every hook of its step, and numba counted a
reference to each array at the entry and exit of every call: for a small assembly that
counting was nine tenths of a step (docs/benchmarks.md, "Reference counting"). Nothing the
step calls may allocate an array then (numba refuses to compile one that does, naming it):
the step works in the run's scratch arrays, made before the loop starts. Nor does a
kernel of the step return an array (it returns numbers and flags): a kernel compiled
elsewhere with reference counting would hand the loop a reference it never gives back.
"""

from __future__ import annotations

import types
from collections import Counter
from typing import Any, Callable

from numba import njit as numba_njit
from numba.core.registry import CPUDispatcher

#: Appended to a kernel's qualified name for its Python entry, so that numba's on-disk
#: cache keeps the two apart (it names cache files by module and qualified name).
ENTRY_SUFFIX = "__python_entry"

#: How many times Python has called each kernel (by module and name): each one compiled its
#: entry at its first call.
PYTHON_CALLS: Counter[str] = Counter()

#: Compile options of a kernel: the wrappers only a call from Python or C needs left out.
WITHOUT_WRAPPERS = {"no_cpython_wrapper": True, "no_cfunc_wrapper": True}

#: Compile options of the time loop: no reference counting (numba's NRT) in it or in any
#: kernel it calls (they inherit the option); none of them may allocate.
NO_REFCOUNT = {"_nrt": False}


class Kernel(CPUDispatcher):
    """A function numba compiles without its Python and C wrappers (callable from compiled
    code); called from Python, it runs its entry, compiled once with the wrappers."""

    _entry: CPUDispatcher | None = None
    _entry_options: dict = {}

    def __call__(self, *args, **kwargs):
        PYTHON_CALLS[f"{self.py_func.__module__}.{self.py_func.__qualname__}"] += 1
        return self.python_entry()(*args, **kwargs)

    def python_entry(self) -> CPUDispatcher:
        """The same function compiled with numba's wrappers (built at the first call)."""
        if self._entry is None:
            f = self.py_func
            copy = types.FunctionType(f.__code__, f.__globals__, f.__name__, f.__defaults__, f.__closure__)
            copy.__kwdefaults__ = f.__kwdefaults__
            copy.__qualname__ = f"{f.__qualname__}{ENTRY_SUFFIX}"
            copy.__doc__ = f.__doc__
            self._entry = numba_njit(**self._entry_options)(copy)
        return self._entry


def njit(function: Callable | None = None, *, entry: bool = False, **options: Any):
    """numba.njit for granplate's kernels (`@njit`, `@njit(cache=True, ...)`), compiled
    without the Python and C wrappers; entry=True: a function the driver calls from
    Python, compiled with them (numba's own njit)."""

    def decorate(f: Callable):
        if entry:
            return numba_njit(**options)(f)
        disp = numba_njit(**options, **WITHOUT_WRAPPERS)(f)
        if not isinstance(disp, CPUDispatcher):  # NUMBA_DISABLE_JIT: the plain function
            return disp
        disp.__class__ = Kernel  # numba's own dispatcher, its Python call sent to the entry
        disp._entry_options = options
        return disp

    return decorate(function) if function is not None else decorate

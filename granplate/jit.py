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
reference counting. The loop hands the run's named tuples of arrays (some 200 arrays) to
every hook of its step, and numba counted a reference to each array at the entry and exit
of every call: for a small assembly that counting was nine tenths of a step
(docs/benchmarks.md, "Reference counting"). Nothing the step calls may allocate an array
then (numba refuses to compile one that does, naming it): the step works in the run's
scratch arrays, made before the loop starts. Nor does a kernel of the step return an
array (it returns numbers and flags).

Every kernel sets `NO_REFCOUNT` itself. numba would otherwise compile a kernel that does
not set it as its first caller is compiled, keep that one machine code for every caller,
and keep it in its on-disk cache: a loop kernel first called from Python (a test, a
session) or from a set-up function counted references in every later run's loop, which
then took 1.8x as long (docs/benchmarks.md, "A kernel's code whoever calls it first").
A kernel that makes arrays (its scratch, its result) says so, `njit(refcount=True)`: it
is compiled with the counting, whoever calls it, and so frees the arrays it makes itself
(an elastic body's contact pass, which the loop calls). It returns arrays only to a
kernel that counts too.
"""

from __future__ import annotations

import types
from collections import Counter
from typing import Any, Callable

from numba import njit as numba_njit
from numba.core.errors import ForceLiteralArg, NumbaError
from numba.core.registry import CPUDispatcher

#: Appended to a kernel's qualified name for its Python entry, so that numba's on-disk
#: cache keeps the two apart (it names cache files by module and qualified name).
ENTRY_SUFFIX = "__python_entry"

#: How many times Python has called each kernel (by module and name): each one compiled its
#: entry at its first call.
PYTHON_CALLS: Counter[str] = Counter()

#: Compile options of a kernel: the wrappers only a call from Python or C needs left out.
WITHOUT_WRAPPERS = {"no_cpython_wrapper": True, "no_cfunc_wrapper": True}

#: Compile options of the time loop and of every kernel (but those made with refcount=True):
#: no reference counting (numba's NRT); none of them may allocate.
NO_REFCOUNT = {"_nrt": False}

#: Compile options of a kernel that makes arrays (njit(refcount=True)): reference counting
#: (numba's default), whoever calls it.
COUNTED = {"_nrt": True}


class Kernel(CPUDispatcher):
    """A function numba compiles without its Python and C wrappers (callable from compiled
    code); called from Python, it runs its entry, compiled once with the wrappers.

    Compiled without reference counting (NO_REFCOUNT) whoever calls it first, or with it
    where made with refcount=True (COUNTED, `njit`)."""

    _entry: CPUDispatcher | None = None
    _entry_options: dict = {}

    def compile(self, sig):
        """numba's compile; a kernel compiled without reference counting that fails to (it
        makes arrays) gets a note saying so."""
        try:
            return super().compile(sig)
        except ForceLiteralArg:  # (numba asking for literal arguments: not a failure)
            raise
        except NumbaError as e:
            if self.targetoptions.get("_nrt") is False:
                e.add_note(
                    f"granplate: {self.py_func.__module__}.{self.py_func.__qualname__} is compiled without "
                    "reference counting (granplate.jit.NO_REFCOUNT); if it makes arrays, mark it "
                    "njit(refcount=True)."
                )
            raise

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


def njit(function: Callable | None = None, *, entry: bool = False, refcount: bool = False, **options: Any):
    """numba.njit for granplate's kernels (`@njit`, `@njit(cache=True, ...)`), compiled
    without the Python and C wrappers and without reference counting (NO_REFCOUNT), whoever
    calls it first; refcount=True: a kernel that makes arrays, compiled with the counting
    (COUNTED), whoever calls it; entry=True: a function the driver calls from Python,
    compiled with the wrappers (numba's own njit)."""

    def decorate(f: Callable):
        if entry:
            return numba_njit(**options)(f)
        pinned = COUNTED if refcount else NO_REFCOUNT
        disp = numba_njit(**{**pinned, **options}, **WITHOUT_WRAPPERS)(f)
        if not isinstance(disp, CPUDispatcher):  # NUMBA_DISABLE_JIT: the plain function
            return disp
        disp.__class__ = Kernel  # numba's own dispatcher, its Python call sent to the entry
        disp._entry_options = options
        return disp

    return decorate(function) if function is not None else decorate

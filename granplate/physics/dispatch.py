"""Dispatch on an id among functions registered by name (a contact law, a drive profile):
a compiled chain of compares, one per registered function, each compiled inline, and the
check that a registered module gives the functions its kind needs. physics.laws builds the
contact laws' dispatch with it, physics.drives the drive profiles'.
"""

from __future__ import annotations

import importlib
from types import ModuleType

from granplate.jit import njit


def checked_module(what: str, path: str, functions: tuple[str, ...]) -> ModuleType:
    """The module at `path`, checked to give every one of `functions` (else an ImportError
    naming `what` and the missing ones)."""
    module = importlib.import_module(path)
    missing = [f for f in functions if not hasattr(module, f)]
    if missing:
        raise ImportError(f"{what}: module {module.__name__} lacks {', '.join(missing)}")
    return module


def pick_of(functions: tuple, arity: int, ids: tuple[int, ...] | None = None, default=None):
    """A compiled function (law, a0, ..., a[arity-1]) -> functions[k](a0, ...) for the k
    whose id is `law` (ids[k]; None: k itself): one compare per function before the law's.
    default: the function for an id not in ids (None: the last function is taken without a
    compare). Compiled inline (`inline="always"`), like the laws' functions: the chain costs
    the caller its compares only. The source of each link is written for its arity (numba
    compiles no call with *args to an inlined function)."""
    ids = tuple(range(len(functions))) if ids is None else tuple(ids)
    names = ", ".join(f"a{k}" for k in range(arity))
    chain = default
    if chain is None:
        functions, ids, chain = functions[:-1], ids[:-1], _link(f"return HEAD({names})", names, HEAD=functions[-1])
    else:
        chain = _link(f"return HEAD({names})", names, HEAD=default)
    for function, law in zip(reversed(functions), reversed(ids)):
        body = f"if law == {int(law)}:\n        return HEAD({names})\n    return TAIL(law, {names})"
        chain = _link(body, names, HEAD=function, TAIL=chain)
    return chain


def _link(body: str, names: str, **space):
    """One compiled link of a `pick_of` chain: def pick(law, names): body, with `space`
    (the functions it calls) as its globals."""
    source = f"def pick(law, {names}):\n    {body}\n"
    exec(compile(source, "<granplate.physics.dispatch>", "exec"), space)
    return njit(inline="always")(space["pick"])

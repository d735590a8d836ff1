"""The normal law of one contact, chosen by its law id, the coefficient row's column
COEF_NLAW: the laws of setup.law_registry's NORMAL_LAW_REGISTRY, in its order (Hertz's,
eq. 2, physics.hertz; Thornton's, docs/model.md section 3.6, physics.plastic; "johnson",
section 3.10, physics.cavity), each with the contact's history: its largest overlap
delta_max and a rate factor (for "johnson", Y(rate) / Y, 0 while unset). One dispatch
function per response kind: `normal_law_response` (force, viscous power, stored energy,
plastic work), `normal_law_force` (the force alone), `normal_law_slopes` (Newton's slopes)
and `normal_law_rate` (the rate factor as the largest overlap grows), and `law_columns`
(the law's coefficient columns, at set-up).

The time loop calls these for every contact kind (granule-granule, granule-wall,
granule-plate, granule-body). Each dispatch is built here from the registry: a chain of
compares on the law id, one per law in the registry's order, each calling that law
module's function of the same kind (`law_response`, `law_force`, `law_slopes`,
`law_rate`); the chain and the laws' functions are compiled inline (`inline="always"`),
so a contact costs one call from the loop whatever its law, and a Hertz contact one
compare (its id is 0): elastic runs stay bitwise what they were before the plastic laws
existed. A new normal law is its module and one line of the registry
(docs/architecture.md, "Adding a normal law").

Cost (docs/benchmarks.md, "Contacts that yield"): a contact under a yielding law whose
overlap and largest overlap are both at or below its yield overlap COEF_DY takes Hertz's
code at the top of its law's function, before any plastic arithmetic.
"""

from __future__ import annotations

import importlib
from types import ModuleType

import numpy as np

from granplate.jit import njit
from granplate.physics.contact import COEF_NLAW
from granplate.setup.law_registry import NORMAL_LAW_REGISTRY

#: the functions every normal law module gives (physics.hertz shows the signatures)
LAW_FUNCTIONS = ("law_response", "law_force", "law_slopes", "law_rate", "law_columns")


def law_module(name: str) -> ModuleType:
    """The module of the registered normal law `name`, checked to give every LAW_FUNCTIONS."""
    module = importlib.import_module(NORMAL_LAW_REGISTRY[name].module)
    missing = [f for f in LAW_FUNCTIONS if not hasattr(module, f)]
    if missing:
        raise ImportError(f"normal law {name!r}: module {module.__name__} lacks {', '.join(missing)}")
    return module


def pick_of_six(functions: tuple, first: int = 0):
    """A compiled function (law, a, b, c, d, e, f) -> functions[law - first](a, ..., f): one
    compare per function before the law's (the last is taken without a compare)."""
    head = functions[0]
    if len(functions) == 1:

        @njit(cache=True, inline="always")
        def last(law, a, b, c, d, e, f):
            return head(a, b, c, d, e, f)

        return last
    tail = pick_of_six(functions[1:], first + 1)

    @njit(cache=True, inline="always")
    def pick(law, a, b, c, d, e, f):
        if law == first:
            return head(a, b, c, d, e, f)
        return tail(law, a, b, c, d, e, f)

    return pick


def pick_of_four(functions: tuple, first: int = 0):
    """`pick_of_six` for functions of four arguments."""
    head = functions[0]
    if len(functions) == 1:

        @njit(cache=True, inline="always")
        def last(law, a, b, c, d):
            return head(a, b, c, d)

        return last
    tail = pick_of_four(functions[1:], first + 1)

    @njit(cache=True, inline="always")
    def pick(law, a, b, c, d):
        if law == first:
            return head(a, b, c, d)
        return tail(law, a, b, c, d)

    return pick


_MODULES = tuple(law_module(name) for name in NORMAL_LAW_REGISTRY)
_RESPONSE = pick_of_six(tuple(m.law_response for m in _MODULES))
_FORCE = pick_of_six(tuple(m.law_force for m in _MODULES))
_SLOPES = pick_of_four(tuple(m.law_slopes for m in _MODULES))
_RATE = pick_of_six(tuple(m.law_rate for m in _MODULES))


@njit(cache=True)
def normal_law_response(delta: float, delta_dot: float, coef, delta_max: float, rate: float, clip: bool):
    """(|N| [N], viscous power [W], stored elastic energy [J], plastic work past delta_max [J])
    of one contact in touch (delta > 0) with coefficient row `coef` (physics.contact's
    columns), largest overlap so far delta_max [m] and rate factor `rate` (read only by the
    laws that use them)."""
    return _RESPONSE(coef[COEF_NLAW], delta, delta_dot, coef, delta_max, rate, clip)


@njit(cache=True)
def normal_law_force(delta: float, delta_dot: float, coef, delta_max: float, rate: float, clip: bool) -> float:
    """|N| [N] of `normal_law_response` alone."""
    return _FORCE(coef[COEF_NLAW], delta, delta_dot, coef, delta_max, rate, clip)


@njit(cache=True)
def normal_law_slopes(delta: float, coef, delta_max: float, rate: float):
    """dN/d(delta) [N/m] and dN/d(delta rate) [N s/m] of `normal_law_response` in touch."""
    return _SLOPES(coef[COEF_NLAW], delta, coef, delta_max, rate)


@njit(cache=True, inline="always")
def normal_law_rate(d: float, d_old: float, t: float, t_old: float, rate: float, coef) -> float:
    """A contact's rate factor once its largest overlap grows from d_old [m] (reached at
    t_old [s]) to d [m] (at t [s]), as its law says (unchanged but for the law "johnson",
    which fixes its yield strength as the contact first passes yield)."""
    return _RATE(coef[COEF_NLAW], d, d_old, t, t_old, rate, coef)


def law_columns(name: str, softer, e_star: float, r_star: float, length: float) -> np.ndarray:
    """The normal law `name`'s coefficient columns COEF_DY..COEF_XH of a contact whose
    softer body is the Material `softer`, with E* [Pa] and R* [m], `length` [m] the length
    that makes its approach speed a strain rate (the sum of the radii, a diameter against a
    rigid body)."""
    return law_module(name).law_columns(softer, e_star, r_star, length)

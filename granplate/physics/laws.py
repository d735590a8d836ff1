"""The contact laws of one contact, chosen by their law ids: the tangential law's by the
coefficient row's column COEF_TLAW (the second half of this module), the normal law's by
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

from types import ModuleType
from typing import NamedTuple

import numpy as np

from granplate.jit import njit
from granplate.physics.dispatch import checked_module, pick_of
from granplate.physics.contact import COEF_NLAW, COEF_TLAW
from granplate.setup.law_registry import NORMAL_LAW_REGISTRY, TANGENTIAL_LAW_REGISTRY, TangentialLaw

#: the functions every normal law module gives (physics.hertz shows the signatures)
LAW_FUNCTIONS = ("law_response", "law_force", "law_slopes", "law_rate", "law_columns")


def law_module(name: str) -> ModuleType:
    """The module of the registered normal law `name`, checked to give every LAW_FUNCTIONS."""
    return checked_module(f"normal law {name!r}", NORMAL_LAW_REGISTRY[name].module, LAW_FUNCTIONS)


_MODULES = tuple(law_module(name) for name in NORMAL_LAW_REGISTRY)
_RESPONSE = pick_of(tuple(m.law_response for m in _MODULES), 6)
_FORCE = pick_of(tuple(m.law_force for m in _MODULES), 6)
_SLOPES = pick_of(tuple(m.law_slopes for m in _MODULES), 4)
_RATE = pick_of(tuple(m.law_rate for m in _MODULES), 6)


@njit(cache=True)
def normal_law_response(delta: float, delta_dot: float, coef, delta_max: float, rate: float, clip: bool):
    """(|N| [N], viscous power [W], stored elastic energy [J], plastic work past delta_max [J])
    of one contact in touch (delta > 0) with coefficient row `coef` (physics.contact's
    columns), largest overlap so far delta_max [m] and rate factor `rate` (read only by the
    laws that use them)."""
    return _RESPONSE(coef[COEF_NLAW], delta, delta_dot, coef, delta_max, rate, clip)


@njit(cache=True, inline="always")
def normal_law_response_inline(delta: float, delta_dot: float, coef, delta_max: float, rate: float, clip: bool):
    """`normal_law_response` compiled into its caller, for the one loop where a call per
    contact shows: the velocity-Verlet pair loop in space (solver.granular3d.pair_forces;
    docs/benchmarks.md). Elsewhere the call keeps the callers' compilation short."""
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


# -- Tangential laws (setup.law_registry's TANGENTIAL_LAW_REGISTRY, ids in its order, the
# coefficient row's column COEF_TLAW). A rate law's force follows from |N| and the slip
# rate: the rate passes (every force pass of a scheme, the split friction, Newton's
# Jacobian, criterion 8) reach it through `tangential_friction`, `tangential_slopes` and
# `tangential_relaxed_slip`, which give a contact under a history law no rate friction. A
# history law (Mindlin's) keeps a tangential displacement per contact (the history columns
# HIST_XI.., model.inputs): the history passes (solver.mindlin_history, the RK4 stages of
# solver.mindlin_rk4) reach it through `keeps_history` and the `tangential_*` functions of
# its history. physics.tanh_friction and physics.mindlin show the signatures.

#: the functions a rate law's module gives
RATE_FUNCTIONS = ("law_friction", "law_slopes", "law_relaxed_slip", "law_columns")
#: the functions a history law's module gives
HISTORY_FUNCTIONS = ("law_scale", "law_stiffness", "law_energy", "law_step", "law_stage", "law_columns")


def tangential_module(name: str, law: TangentialLaw | None = None) -> ModuleType:
    """The module of the registered tangential law `name` (or of `law`), checked to give
    every function of its kind (HISTORY_FUNCTIONS or RATE_FUNCTIONS)."""
    law = TANGENTIAL_LAW_REGISTRY[name] if law is None else law
    return checked_module(f"tangential law {name!r}", law.module, HISTORY_FUNCTIONS if law.history else RATE_FUNCTIONS)


@njit(cache=True, inline="always")
def _yes() -> bool:
    return True


@njit(cache=True, inline="always")
def _no() -> bool:
    return False


@njit(cache=True, inline="always")
def _no_friction(n_abs, v_t, coef) -> float:
    return 0.0


@njit(cache=True, inline="always")
def _no_slopes(n_abs, v_t, coef):
    return 0.0, 0.0


@njit(cache=True, inline="always")
def _slip_kept(v_t, n_abs, coef, inv_mass_t, dt) -> float:
    return v_t


@njit(cache=True, inline="always")
def _no_history_scale(coef, r_star, delta) -> float:
    return 0.0


@njit(cache=True, inline="always")
def _no_history_stiffness(coef, a) -> float:
    return 0.0


@njit(cache=True, inline="always")
def _no_history_energy(coef, a, xx, xy, xz) -> float:
    return 0.0


@njit(cache=True, inline="always")
def _no_history_step(xx, xy, xz, a, a_old, coef, delta, nx, ny, nz, vx, vy, vz, dt, n_abs, f0x, f0y, f0z):
    return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0


@njit(cache=True, inline="always")
def _no_history_stage(xx, xy, xz, a, a_old, coef, delta, nx, ny, nz, ix, iy, iz, vx, vy, vz, n_abs):
    return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0


class TangentialDispatch(NamedTuple):
    """The compiled dispatch functions on a tangential law id, built from a registry
    (`tangential_dispatch`): each (law, arguments of the law modules' function) -> its
    value; an id of the other kind gets the default (no friction, no history)."""

    keeps_history: object
    friction: object
    slopes: object
    relaxed_slip: object
    scale: object
    stiffness: object
    energy: object
    step: object
    stage: object


def tangential_dispatch(registry: dict[str, TangentialLaw]) -> TangentialDispatch:
    """The dispatch functions of the tangential laws of `registry` (ids in its order)."""
    laws = [(k, law, tangential_module(name, law)) for k, (name, law) in enumerate(registry.items())]
    rate = [(k, m) for k, law, m in laws if not law.history]
    held = [(k, m) for k, law, m in laws if law.history]

    def chain(kind: list, function: str, arity: int, default):
        return pick_of(tuple(getattr(m, function) for _, m in kind), arity, tuple(k for k, _ in kind), default)

    return TangentialDispatch(
        pick_of(tuple(_yes for _ in held), 0, tuple(k for k, _ in held), _no),
        chain(rate, "law_friction", 3, _no_friction),
        chain(rate, "law_slopes", 3, _no_slopes),
        chain(rate, "law_relaxed_slip", 5, _slip_kept),
        chain(held, "law_scale", 3, _no_history_scale),
        chain(held, "law_stiffness", 2, _no_history_stiffness),
        chain(held, "law_energy", 5, _no_history_energy),
        chain(held, "law_step", 18, _no_history_step),
        chain(held, "law_stage", 17, _no_history_stage),
    )


_T = tangential_dispatch(TANGENTIAL_LAW_REGISTRY)
_KEEPS, _FRICTION, _TSLOPES, _RELAXED = _T.keeps_history, _T.friction, _T.slopes, _T.relaxed_slip
_TSCALE, _TSTIFF, _TENERGY, _TSTEP, _TSTAGE = _T.scale, _T.stiffness, _T.energy, _T.step, _T.stage


@njit(cache=True, inline="always")
def keeps_history(coef) -> bool:
    """Whether the tangential law of coefficient row `coef` keeps a history per contact."""
    return _KEEPS(coef[COEF_TLAW])


@njit(cache=True)
def tangential_friction(n_abs: float, v_t: float, coef) -> float:
    """A rate law's signed friction f [N] at |N| = n_abs [N] and slip rate v_t [m/s]; on the
    first body it acts along -t (0 under a history law)."""
    return _FRICTION(coef[COEF_TLAW], n_abs, v_t, coef)


@njit(cache=True)
def tangential_slopes(n_abs: float, v_t: float, coef):
    """A rate law's (d f / d|N| [-], d f / d v_t [N s/m]) (0, 0 under a history law)."""
    return _TSLOPES(coef[COEF_TLAW], n_abs, v_t, coef)


@njit(cache=True)
def tangential_relaxed_slip(v_t: float, n_abs: float, coef, inv_mass_t: float, dt: float) -> float:
    """The slip rate [m/s] after a rate law alone acted for dt [s] at a contact of
    tangential inverse mass inv_mass_t [1/kg], |N| held: the law's exact flow (unchanged
    under a history law)."""
    return _RELAXED(coef[COEF_TLAW], v_t, n_abs, coef, inv_mass_t, dt)


@njit(cache=True, inline="always")
def tangential_scale(coef, r_star: float, delta: float) -> float:
    """A history law's scale of its history at overlap delta [m] of a contact of R* [m]
    (Mindlin's: the contact radius [m])."""
    return _TSCALE(coef[COEF_TLAW], coef, r_star, delta)


@njit(cache=True, inline="always")
def tangential_stiffness(coef, a: float) -> float:
    """A history law's sticking stiffness k_t [N/m] at scale a."""
    return _TSTIFF(coef[COEF_TLAW], coef, a)


@njit(cache=True, inline="always")
def tangential_energy(coef, a: float, xx: float, xy: float, xz: float) -> float:
    """The energy [J] a history law stores in the history xi (3) [m] at scale a."""
    return _TENERGY(coef[COEF_TLAW], coef, a, xx, xy, xz)


@njit(cache=True, inline="always")
def tangential_step(xx, xy, xz, a, a_old, coef, delta, nx, ny, nz, vx, vy, vz, dt, n_abs, f0x, f0y, f0z):
    """A history law's step of dt [s] (physics.mindlin.law_step's arguments and values),
    compiled into its caller (solver.mindlin_history.mindlin_contact: the pair loops'
    tangential step, a call per contact in touch)."""
    return _TSTEP(coef[COEF_TLAW], xx, xy, xz, a, a_old, coef, delta, nx, ny, nz, vx, vy, vz, dt, n_abs, f0x, f0y, f0z)


@njit(cache=True)
def tangential_stage(xx, xy, xz, a, a_old, coef, delta, nx, ny, nz, ix, iy, iz, vx, vy, vz, n_abs):
    """A history law's force at one stage of a multi-stage step (physics.mindlin.law_stage)."""
    return _TSTAGE(coef[COEF_TLAW], xx, xy, xz, a, a_old, coef, delta, nx, ny, nz, ix, iy, iz, vx, vy, vz, n_abs)


def tangential_columns(name: str, coef: np.ndarray, compliance: np.ndarray, contact) -> None:
    """The tangential law `name`'s columns of the rows `coef` in place, its id into COEF_TLAW
    (compliance: each row's 1/G* [1/Pa], the two bodies' (2 - nu)/G summed, a rigid body's
    0; contact: the scenario's Contact)."""
    tangential_module(name).law_columns(coef, compliance, contact)
    coef[:, COEF_TLAW] = list(TANGENTIAL_LAW_REGISTRY).index(name)

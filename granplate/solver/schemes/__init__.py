"""The coupling schemes, one module each, behind one interface, and their registry.

A scheme module defines NAME, a `Scratch` named tuple (its own scratch arrays),
`new_scratch(ng, nm, nk, body=None, threads=1)` (sized for the model's elastic body in
space, `body`, whose arrays it does not hold), and nine compiled hooks, each taking its
Scratch first. The elastic bodies are the loop's own arrays, beside the granules' g: p,
the modal plate (model.inputs.PlateArrays: the plane's plate, its contacts in g's `pc_*`
rows; no modes in space) and b, the elastic body in space (model.inputs.BodyArrays with
this run's contact state, or NoBodyArrays: none). A scheme that drives no body in space
takes b and leaves it; one that does chooses its code by b's type when the loop compiles
(solver.body.by_body):

    plan(sw, count, cfg, pos, rem) -> (level, h, slot, land)
    prepare_level(sw, h, p, slot)
    attempt(sw, t, h, slot, st, g, p, b, cfg, w) -> (converged, iterations, worst, e_pot, rate)
    judge(sw, t, h, slot, level, ratio, e_pot, st, g, p, b, cfg, w) -> (err, retry, work, fric_work)
    commit(sw, t, h, slot, plate_work, fric_work, st, g, p, b, cfg, w) -> plate work [J]
    next_level(sw, h, slot, level, err, lam_max, rate, t_now, cfg) -> (level, h_new)
    contact_placed(sw, k, st, p)
    contacts_moved(sw, t, st, p, cfg)
    start(sw, t, st, g, b, cfg) -> (contact energy, residual energy) [J] at t = 0

and five optional hooks:

    body_sensor_loads(sw, b, load)   half the normal force of each granule's contact with the
                                     elastic body in space b added to its sensor reading
                                     load[i] [N] (docs/model.md section 3.15); absent from a
                                     scheme whose bodies are the granules and the plate alone
                                     (then it adds nothing)
    commit_histories(sw, t, g, cfg)  the contacts' histories of an accepted step ending at
                                     t [s]; absent: every contact's end overlap committed
                                     after the step (solver.granular.commit_histories, the
                                     pairs in blocks on every core with cfg.threads > 1)
    largest_move(sw) -> float        the largest squared distance [m^2] a granule has moved
                                     since the contact list's reference (Work.yref), where
                                     the step measured it as it moved them (the contact
                                     watch then screens nothing itself); absent: -1, not
                                     measured (solver.contacts.watch_contacts)
    step_kinetic_energies(sw, y, g)  the granules' (KE_x, KE_y, KE_z, KE_rot) [J] at state
                                     y for the energy check after each step; absent: summed
                                     serially (solver.dimension.kinetic_energies)
    steps_in_place(sw, g) -> bool    whether `attempt` wrote the step's end state and
                                     derivatives into st.y and st.k1 themselves (a scheme
                                     whose every step is accepted); absent: False, they
                                     wait in w.ynew and w.kend and the loop copies them in

`start` gives what the bodies hold at t = 0 beyond the loop's own energies (the contacts
of the elastic body in space b, solver.body; (0, 0) without one). The two before it keep the scheme's own driving-DOF state true when the plate contacts' rows
of Phi_d change between steps (solver/interface.py, docs/model.md section 3.5):
`contact_placed` after plate contact k's rows were set with the modes held (a patch
contact added), `contacts_moved` after loaded patch contacts moved (what depends on
Phi_d^T F at t_n).

The time loop (solver/loop.py) calls the hooks below; numba picks the scheme's function
from the type of the scratch at compile time (one compiled loop per scheme, each cached
on disk; no Python and no function pointer per step). Hooks called every step take
only the arrays they need: a call that passes the big state tuples costs ~0.4 us. Adding a scheme: write its module
and add it to SCHEMES (and its name to model.inputs.SCHEME_NAMES).
"""

from __future__ import annotations

from types import ModuleType

from numba.extending import overload

from granplate.jit import njit

from granplate.model.inputs import SCHEME_NAMES
from granplate.solver.dimension import kinetic_energies as kinetic_energies_serial
from granplate.solver.blocks import commit_histories_blocks
from granplate.solver.granular import commit_histories as commit_every_history
from granplate.solver.schemes import implicit, paper, verlet

#: the registered schemes by name, in the order of model.inputs.SCHEME_NAMES.
SCHEMES: dict[str, ModuleType] = {m.NAME: m for m in (paper, implicit, verlet)}
_BY_SCRATCH = {m.Scratch: m for m in SCHEMES.values()}
assert tuple(SCHEMES) == SCHEME_NAMES, "model.inputs.SCHEME_NAMES and SCHEMES disagree"


def scheme(name_or_number: str | int) -> ModuleType:
    """The scheme module called `name_or_number` (a name or Config.scheme)."""
    name = name_or_number
    if isinstance(name_or_number, int):
        if not 0 <= name_or_number < len(SCHEME_NAMES):
            raise ValueError(f"scheme number {name_or_number}: allowed 0 to {len(SCHEME_NAMES) - 1}")
        name = SCHEME_NAMES[name_or_number]
    if name not in SCHEMES:
        raise ValueError(f"solver.scheme = {name!r}: allowed {', '.join(SCHEMES)}")
    return SCHEMES[name]


def _hook_of(sw, name: str):
    """The compiled hook `name` of the scheme whose Scratch type is `sw` (numba type)."""
    module = _BY_SCRATCH.get(getattr(sw, "instance_class", None))
    return None if module is None else getattr(module, name)


def plan(sw, count, cfg, pos, rem):
    """The scheme's level and step (see the module docstring)."""
    raise NotImplementedError("compiled use only")


def prepare_level(sw, h, p, slot):
    """The scheme's per-level matrices."""
    raise NotImplementedError("compiled use only")


def attempt(sw, t, h, slot, st, g, p, b, cfg, w):
    """The scheme's trial step."""
    raise NotImplementedError("compiled use only")


def judge(sw, t, h, slot, level, ratio, e_pot, st, g, p, b, cfg, w):
    """The scheme's acceptance test of a converged trial step."""
    raise NotImplementedError("compiled use only")


def commit(sw, t, h, slot, plate_work, fric_work, st, g, p, b, cfg, w):
    """The scheme's plate update of an accepted step."""
    raise NotImplementedError("compiled use only")


def next_level(sw, h, slot, level, err, lam_max, rate, t_now, cfg):
    """The scheme's next step."""
    raise NotImplementedError("compiled use only")


def contact_placed(sw, k, st, p):
    """The scheme's state at plate contact k's rows of Phi_d, just set."""
    raise NotImplementedError("compiled use only")


def contacts_moved(sw, t, st, p, cfg):
    """The scheme's state after loaded patch contacts moved at t [s]."""
    raise NotImplementedError("compiled use only")


@overload(plan, inline="always")
def _plan(sw, count, cfg, pos, rem):
    fn = _hook_of(sw, "plan")
    if fn is not None:
        return lambda sw, count, cfg, pos, rem: fn(sw, count, cfg, pos, rem)


@overload(prepare_level, inline="always")
def _prepare_level(sw, h, p, slot):
    fn = _hook_of(sw, "prepare_level")
    if fn is not None:
        return lambda sw, h, p, slot: fn(sw, h, p, slot)


@overload(attempt, inline="always")
def _attempt(sw, t, h, slot, st, g, p, b, cfg, w):
    fn = _hook_of(sw, "attempt")
    if fn is not None:
        return lambda sw, t, h, slot, st, g, p, b, cfg, w: fn(sw, t, h, slot, st, g, p, b, cfg, w)


@overload(judge, inline="always")
def _judge(sw, t, h, slot, level, ratio, e_pot, st, g, p, b, cfg, w):
    fn = _hook_of(sw, "judge")
    if fn is not None:
        return lambda sw, t, h, slot, level, ratio, e_pot, st, g, p, b, cfg, w: fn(
            sw, t, h, slot, level, ratio, e_pot, st, g, p, b, cfg, w
        )


@overload(commit, inline="always")
def _commit(sw, t, h, slot, plate_work, fric_work, st, g, p, b, cfg, w):
    fn = _hook_of(sw, "commit")
    if fn is not None:
        return lambda sw, t, h, slot, plate_work, fric_work, st, g, p, b, cfg, w: fn(
            sw, t, h, slot, plate_work, fric_work, st, g, p, b, cfg, w
        )


@overload(next_level, inline="always")
def _next_level(sw, h, slot, level, err, lam_max, rate, t_now, cfg):
    fn = _hook_of(sw, "next_level")
    if fn is not None:
        return lambda sw, h, slot, level, err, lam_max, rate, t_now, cfg: fn(
            sw, h, slot, level, err, lam_max, rate, t_now, cfg
        )


@overload(contact_placed, inline="always")
def _contact_placed(sw, k, st, p):
    fn = _hook_of(sw, "contact_placed")
    if fn is not None:
        return lambda sw, k, st, p: fn(sw, k, st, p)


@overload(contacts_moved, inline="always")
def _contacts_moved(sw, t, st, p, cfg):
    fn = _hook_of(sw, "contacts_moved")
    if fn is not None:
        return lambda sw, t, st, p, cfg: fn(sw, t, st, p, cfg)


def start(sw, t, st, g, b, cfg):
    """The scheme's own energies at t = 0."""
    raise NotImplementedError("compiled use only")


@overload(start, inline="always")
def _start(sw, t, st, g, b, cfg):
    fn = _hook_of(sw, "start")
    if fn is not None:
        return lambda sw, t, st, g, b, cfg: fn(sw, t, st, g, b, cfg)


def _optional_hook(sw, name: str, default):
    """The optional hook `name` of the scheme whose Scratch type is `sw` (numba type), or
    `default` (a compiled function of the same signature) where the scheme has none; None
    where sw is no scheme's scratch (numba looks further)."""
    module = _BY_SCRATCH.get(getattr(sw, "instance_class", None))
    return None if module is None else getattr(module, name, default)


@njit(cache=True)
def _no_body_loads(sw, b, load):
    """A scheme without an elastic body in space adds nothing to the sensors."""
    return


@njit(cache=True)
def _commit_after_step(sw, t, g, cfg):
    """Every contact's end overlap committed after the step (the pairs in blocks on every
    core with cfg.threads > 1)."""
    if cfg.threads > 1:
        commit_histories_blocks(t, g, cfg.threads)
    else:
        commit_every_history(t, g)


@njit(cache=True)
def _serial_kinetic_energies(sw, y, g):
    """The granules' kinetic energies summed serially (solver.dimension)."""
    return kinetic_energies_serial(y, g)


@njit(cache=True)
def _moves_unmeasured(sw):
    """A scheme without the hook leaves the contact watch to measure the moves."""
    return -1.0


@njit(cache=True)
def _trial_apart(sw, g):
    """A scheme without the hook writes its trial into the Work arrays (w.ynew, w.kend)."""
    return False


def body_sensor_loads(sw, b, load):
    """The scheme's own body's share of the sensors' readings (none where it has no hook)."""
    raise NotImplementedError("compiled use only")


@overload(body_sensor_loads, inline="always")
def _body_sensor_loads(sw, b, load):
    fn = _optional_hook(sw, "body_sensor_loads", _no_body_loads)
    if fn is not None:
        return lambda sw, b, load: fn(sw, b, load)


def commit_histories(sw, t, g, cfg):
    """The contacts' histories of the accepted step ending at t [s] (the scheme's hook, or
    every contact's end overlap committed after the step)."""
    raise NotImplementedError("compiled use only")


@overload(commit_histories, inline="always")
def _commit_histories(sw, t, g, cfg):
    fn = _optional_hook(sw, "commit_histories", _commit_after_step)
    if fn is not None:
        return lambda sw, t, g, cfg: fn(sw, t, g, cfg)


def step_kinetic_energies(sw, y, g):
    """The granules' kinetic energies at state y for the step's energy check (the scheme's
    hook, or their serial sums)."""
    raise NotImplementedError("compiled use only")


@overload(step_kinetic_energies, inline="always")
def _step_kinetic_energies(sw, y, g):
    fn = _optional_hook(sw, "step_kinetic_energies", _serial_kinetic_energies)
    if fn is not None:
        return lambda sw, y, g: fn(sw, y, g)


def largest_move(sw):
    """The largest squared move of a granule since the contact list's reference [m^2] where
    the scheme's step measured it (the scheme's hook), else -1."""
    raise NotImplementedError("compiled use only")


@overload(largest_move, inline="always")
def _largest_move(sw):
    fn = _optional_hook(sw, "largest_move", _moves_unmeasured)
    if fn is not None:
        return lambda sw: fn(sw)


def steps_in_place(sw, g):
    """Whether the scheme's step wrote its end state and derivatives into the state itself
    (st.y, st.k1; the scheme's hook), so that the loop's acceptance copies nothing; else
    (no hook) they wait in w.ynew, w.kend for it."""
    raise NotImplementedError("compiled use only")


@overload(steps_in_place, inline="always")
def _steps_in_place(sw, g):
    fn = _optional_hook(sw, "steps_in_place", _trial_apart)
    if fn is not None:
        return lambda sw, g: fn(sw, g)

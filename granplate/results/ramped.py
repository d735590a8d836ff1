"""The ramped settling of a poured packing in space (`[layout] settle_softening` > 1;
docs/model.md section 3.14, "Ramped settling").

The granules fall from the loose column (`setup.pouring.loose_column`) with every
contact's stiffness softened by s = 1 / settle_softening (Hertz's A and Mindlin's 8 G*; the
steps as much longer as the contact time, s^(-2/5)), settle held by Mindlin's friction
(settle_friction) and damped by eq. (3)'s damping and Cundall's local damping; once the
kinetic energy is at most RAMP_BELOW x gravity's work the stiffness is raised
geometrically, at most RAMP_FACTOR a chunk, to the real law's (s = 1), the tangential
forces carried over; at s = 1 the settling goes on until the kinetic energy is at most
settle_tolerance x gravity's work and every granule's residual force (its contacts'
elastic forces and its weight: a static balance) is at most settle_residual x its weight.
A packing dropped one by one (layout.drop = "sequential", `setup.deposition`) skips the
fall: it starts at rest, touching, at the stiffness 1 / settle_softening (1 by default).
The compiled steps are `solver.settling`'s; this module lists the contacts (a Verlet list
with a skin, rebuilt when a granule moved half of it), picks the steps and judges the
phases.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time

import numpy as np

from granplate.model.arrays import masses_and_inertias, pair_coefficients, wall_arrays
from granplate.physics.contact import COEF_XT, N_COEF
from granplate.setup import pouring
from granplate.setup.pairs import close_pairs
from granplate.setup.scenario import PouredLayout, Scenario
from granplate.solver import settling as kernel

log = logging.getLogger("granplate")

#: The contact lists' skin, a fraction of the largest radius: pairs closer than the sum of
#: their radii plus it are listed; a granule that moved half of it has the lists rebuilt.
SKIN = 0.4
#: Cundall's local damping lambda [-] of the granules in contact (YADE's default is 0.2).
LOCAL_DAMPING = 0.5
#: The background damping of the spins [1/s]: every spin decays as exp(-SPIN_DAMPING t)
#: besides its torques (a settling device; 0: off, the quenches stop free spins instead).
SPIN_DAMPING = 0.0
#: A chunk of the fall that ends with the kinetic energy at most this fraction of gravity's
#: work (but above RAMP_BELOW) hands the next its state at rest (a quench).
QUENCH_BELOW = 1e-4
#: The background damping of the velocities [1/s] after the fall: v decays as exp(-DRAG t)
#: besides its forces (a settling device, as LAMMPS's fix viscous). 0: off (200 1/s was
#: tried: it slowed the rest phase's rearrangements, which did not end).
DRAG = 0.0
#: Steps of one chunk (the criteria are judged at its end).
CHUNK_STEPS = 1000
#: The stiffness is raised once the kinetic energy is at most this fraction of gravity's work,
#: by at most RAMP_FACTOR over a chunk.
RAMP_BELOW = 1e-6
RAMP_FACTOR = 2.0
#: The step at rest: this fraction of min sqrt(m / K) over the granules, K their contacts'
#: stiffness (`solver.settling.stiffness_sums`; Verlet is stable below sqrt(2 m / K)),
#: and at most STEP_GROWTH times the fall's step at that stiffness.
STATIC_STEP = 0.5
STEP_GROWTH = 4.0

#: Mindlin's tangential damping is turned on (for the rest of the settling) at the
#: BALANCED_CHUNKS-th chunk that ends in balance: a packing in balance is quenched, and one
#: that a quench did not bring to rest still moves freely (rolling, spinning), which that
#: damping takes (`settling_rows`).
BALANCED_CHUNKS = 2


def settling_rows(coef: np.ndarray, x_t: np.ndarray, damped: bool) -> np.ndarray:
    """Contact rows `coef` as the settling runs them (docs/model.md section 3.14): Mindlin's
    tangential damping ratio (COEF_XT) the contacts' own, x_t, where `damped`, else 0. The
    settling runs without it at first (`tangential_damping_on`): under their own weight
    millimetre granules touch with overlaps of nanometres, where that
    damping, x_t c delta^(1/4), holds a granule that rolls or slides off its rest to a
    viscous creep at the slip rate F / eta for tenths of a second; without it the granule
    reaches its new rest in milliseconds and Cundall's damping takes the energy. Where a
    packing in balance still moves after a quench, it is on again and takes what rolls and
    spins freely. A static state is the same with or without a damping: only the path to
    it changes."""
    out = np.ascontiguousarray(coef, float).copy()
    out[:, COEF_XT] = x_t if damped else 0.0
    return out


def tangential_damping_on(p: "Packing", out: "Outcome", lay: PouredLayout) -> bool:
    """Whether the next chunk runs with Mindlin's tangential damping (`settling_rows`): off
    until BALANCED_CHUNKS chunks at the real stiffness have ended in balance (every
    residual force at most settle_residual of a weight), on from then."""
    if p.s >= 1.0 and out.residual <= lay.settle_residual:
        p.balanced += 1
    return p.damped or p.balanced >= BALANCED_CHUNKS


def set_tangential_damping(p: "Packing", damped: bool) -> None:
    """The settling's pair and wall rows with Mindlin's tangential damping on or off
    (`settling_rows`)."""
    if damped == p.damped:
        return
    p.damped = damped
    p.pcoef = settling_rows(p.pcoef, p.xt_pairs, damped)
    p.wcoef = settling_rows(p.wcoef, p.xt_walls, damped)


@dataclasses.dataclass
class Packing:
    """The granules' state and contact lists of a ramped settling (3D arrays, SI units)."""

    scenario: Scenario
    mats: list
    x: np.ndarray
    v: np.ndarray
    w: np.ndarray
    radius: np.ndarray
    mass: np.ndarray
    inertia: np.ndarray
    g: np.ndarray
    walls: np.ndarray
    wcoef: np.ndarray
    whist: np.ndarray
    pairs: np.ndarray
    pcoef: np.ndarray
    phist: np.ndarray
    x_ref: np.ndarray
    f: np.ndarray
    tq: np.ndarray
    touch: np.ndarray
    start: np.ndarray
    s: float
    xt_walls: np.ndarray | None = None  # the wall rows' own tangential damping ratio
    xt_pairs: np.ndarray | None = None  # the listed pairs' own
    damped: bool = False  # Mindlin's tangential damping on (`settling_rows`)
    balanced: int = 0  # chunks at the real stiffness that ended in balance

    @property
    def skin(self) -> float:
        return SKIN * float(self.radius.max())


def packing(s: Scenario, lay: PouredLayout) -> Packing:
    """The dropped granules of `lay` at rest (the loose column, or the deposited packing of
    drop = "sequential"; gravity's work counted from where they were released), its walls
    and their coefficients, at the settling's soft stiffness (`results.pouring.loose_scenario` gives the contacts: damping
    settle_damping, Mindlin's friction settle_friction)."""
    from granplate.results.pouring import loose_scenario, release_centres

    loose = loose_scenario(s, lay, lay.settle_damping, lay.settle_friction)
    n = len(loose.granules)
    x = np.array([[q.x, q.y, q.z] for q in loose.granules], float)
    r = np.array([q.radius for q in loose.granules], float)
    mats = [loose.material(q.material) for q in loose.granules]
    mass, inertia = masses_and_inertias(r, np.array([m.rho for m in mats], float))
    nw = len(loose.walls)
    walls = np.array([(*(np.asarray(q.normal, float) / np.linalg.norm(q.normal)), q.offset) for q in loose.walls])
    wc = np.column_stack([np.repeat(np.arange(n), nw), np.tile(np.arange(nw), n)])
    _, wcoef = wall_arrays(loose, mats, r, mass, wc)
    empty = np.zeros((0, 2), np.int64)
    p = Packing(
        loose,
        mats,
        x,
        np.zeros((n, 3)),
        np.zeros((n, 3)),
        r,
        mass,
        inertia,
        np.asarray(pouring.pour_gravity(s, lay), float),
        walls,
        settling_rows(wcoef, wcoef[:, COEF_XT], False),
        np.zeros((n * nw, kernel.N_HIST)),
        empty,
        np.zeros((0, N_COEF)),
        np.zeros((0, kernel.N_HIST)),
        x.copy(),
        np.zeros((n, 3)),
        np.zeros((n, 3)),
        np.zeros(n, np.int64),
        release_centres(s, lay),
        1.0 / lay.settle_softening,
        xt_walls=np.ascontiguousarray(wcoef[:, COEF_XT], float),
    )
    relist(p)
    kernel.contact_forces(*_force_args(p), p.s, 0.0, False, p.f, p.tq, p.touch)
    return p


def relist(p: Packing) -> None:
    """The pair list rebuilt at the positions now: pairs within the sum of their radii plus
    the skin, their coefficients, the histories of the pairs listed before carried over."""
    r = p.radius
    cand = close_pairs(p.x, 2.0 * float(r.max()) + p.skin)
    if len(cand):
        i, j = cand[:, 0], cand[:, 1]
        cand = cand[np.linalg.norm(p.x[i] - p.x[j], axis=1) < r[i] + r[j] + p.skin]
    n = len(r)
    cand = cand[np.argsort(cand[:, 0] * n + cand[:, 1], kind="stable")]  # keyed i n + j, ascending
    old = p.pairs[:, 0] * n + p.pairs[:, 1]
    new = cand[:, 0] * n + cand[:, 1]
    hist = np.zeros((len(cand), kernel.N_HIST))
    if len(old) and len(new):
        at = np.clip(np.searchsorted(old, new), 0, len(old) - 1)
        hit = old[at] == new
        hist[hit] = p.phist[at[hit]]
    p.pairs = np.ascontiguousarray(cand, np.int64)
    rows = pair_coefficients(p.scenario, p.mats, r, p.mass, p.pairs)
    p.xt_pairs = np.ascontiguousarray(rows[:, COEF_XT], float)
    p.pcoef = settling_rows(rows, p.xt_pairs, p.damped)
    p.phist = hist
    p.x_ref = p.x.copy()


def _force_args(p: Packing) -> tuple:
    return (p.x, p.v, p.w, p.radius, p.mass, p.g, p.pairs, p.pcoef, p.phist, p.walls, p.wcoef, p.whist)


def run_chunk(p: Packing, s_end: float, dt: float, steps: int, drag: float, lam: float) -> None:
    """`steps` steps of dt [s], the stiffness factor from p.s to s_end geometrically, the
    lists rebuilt whenever a granule moved half the skin; drag [1/s]: the velocities'
    background damping, lam [-]: Cundall's local damping."""
    done = 0
    ratio = (s_end / p.s) ** (1.0 / steps)
    while done < steps:
        k = steps - done
        s1 = p.s * ratio**k
        did = kernel.settle_steps(
            p.x, p.v, p.w, p.radius, p.mass, p.inertia, p.g, p.pairs, p.pcoef, p.phist, p.walls, p.wcoef,
            p.whist, p.s, s1, lam, math.exp(-drag * dt), math.exp(-SPIN_DAMPING * dt), dt, k, p.x_ref, 0.5 * p.skin, p.f, p.tq, p.touch,
        )  # fmt: skip
        p.s *= ratio**did
        done += did
        if did < k:
            relist(p)
    p.s = s_end


def kinetic_fraction(p: Packing) -> float:
    """The kinetic energy (translation and rotation) over gravity's work since the drop [-]."""
    ke = 0.5 * float(np.sum(p.mass * np.sum(p.v**2, axis=1)) + np.sum(p.inertia * np.sum(p.w**2, axis=1)))
    work = float(np.sum(p.mass * ((p.x - p.start) @ p.g)))
    return ke / work if work > 0.0 else math.inf


def residual_forces(p: Packing) -> np.ndarray:
    """(n,) each granule's residual force over its weight [-]: the elastic normal forces
    and the tangential springs' forces of its contacts at rest, plus its weight."""
    f, tq, touch = np.zeros_like(p.f), np.zeros_like(p.tq), np.zeros_like(p.touch)
    zero = np.zeros_like(p.v)
    args = (p.x, zero, zero, p.radius, p.mass, p.g, p.pairs, p.pcoef, p.phist.copy(), p.walls, p.wcoef, p.whist.copy())
    kernel.contact_forces(*args, p.s, 0.0, True, f, tq, touch)
    return np.linalg.norm(f, axis=1) / (p.mass * float(np.linalg.norm(p.g)))


def wall_loads(p: Packing) -> np.ndarray:
    """(nw, 4): each wall's normal force [N] and its contacts' tangential force (3) on the granules [N]."""
    return kernel.wall_loads(p.x, p.radius, p.walls, p.wcoef, p.whist, p.s)


def fall_step(s: Scenario, lay: PouredLayout, stiffness: float) -> float:
    """The step [s] of the fall at the stiffness factor: `results.pouring.settling_step`
    (the real law's) times stiffness^(-2/5), as Hertz's contact time."""
    from granplate.results.pouring import settling_step

    return settling_step(s, lay, pouring.pour_gravity(s, lay)) * stiffness ** (-0.4)


def rest_step(p: Packing, s_end: float, fall: float) -> float:
    """The step [s] of a chunk that ends at stiffness s_end: STATIC_STEP min sqrt(m / K),
    K at the contacts' present overlaps and s_end, at most STEP_GROWTH x `fall`."""
    k = kernel.stiffness_sums(p.x, p.radius, p.pairs, p.pcoef, p.walls, p.wcoef, s_end)
    on = k > 0.0
    bound = STATIC_STEP * float(np.sqrt(p.mass[on] / k[on]).min()) if on.any() else math.inf
    return min(bound, STEP_GROWTH * fall)


@dataclasses.dataclass
class Outcome:
    """What a ramped settling reached: simulated time [s], steps, kinetic energy over
    gravity's work, the largest residual force over a weight, wall and CPU seconds, settled."""

    t: float = 0.0
    steps: int = 0
    kinetic: float = math.inf
    residual: float = math.inf
    wall_s: float = 0.0
    cpu_s: float = 0.0
    settled: bool = False
    quenches: int = 0


def _quench(p: Packing, out: Outcome) -> None:
    """The velocities and spins set to zero (free spins about a contact's normal, which
    neither law resists, and granules rolling on the floor stop)."""
    p.v[:] = 0.0
    p.w[:] = 0.0
    out.quenches += 1


def _report(out: Outcome, p: Packing, phase: str, progress: bool, clock: float, cpu: float) -> None:
    """A progress line: the phase, simulated time, stiffness factor, criteria, wall and CPU seconds."""
    line = (
        f"pouring ({phase}): t = {out.t:.4g} s, stiffness x {p.s:.3g}, kinetic / gravity's work = "
        f"{out.kinetic:.3g}, residual force / weight = {out.residual:.3g} "
        f"({time.perf_counter() - clock:.0f} s wall, {time.process_time() - cpu:.0f} s CPU)"
    )
    log.info(line)
    if progress:
        print("granplate: " + line, flush=True)


def settle_ramped(s: Scenario, lay: PouredLayout, progress: bool = False) -> tuple[Packing, Outcome]:
    """The ramped settling of `lay` in `s` (module docstring): the packing reached and what
    it reached. Stops at settle_time of simulated time."""
    import numba

    from granplate.setup.threads import loop_threads

    before = numba.get_num_threads()
    numba.set_num_threads(loop_threads(s.solver.threads, lay.count, "verlet"))
    try:
        return _settle_ramped(s, lay, progress)
    finally:
        numba.set_num_threads(before)


def _settle_ramped(s: Scenario, lay: PouredLayout, progress: bool) -> tuple[Packing, Outcome]:
    """`settle_ramped` on the threads set."""
    clock, cpu = time.perf_counter(), time.process_time()
    p = packing(s, lay)
    out = Outcome()
    falling = lay.drop != "sequential"  # until the kinetic energy first falls to RAMP_BELOW: the fall's step
    while out.t < lay.settle_time:
        ramp = not falling and p.s < 1.0 and out.kinetic <= RAMP_BELOW
        s_end = min(1.0, p.s * RAMP_FACTOR) if ramp else p.s
        fall = fall_step(s, lay, s_end)
        dt = fall if falling else rest_step(p, s_end, fall)
        run_chunk(p, s_end, dt, CHUNK_STEPS, 0.0 if falling else DRAG, LOCAL_DAMPING)
        out.t += dt * CHUNK_STEPS
        out.steps += CHUNK_STEPS
        out.kinetic = kinetic_fraction(p)
        out.residual = float(residual_forces(p).max())
        _report(out, p, "fall" if falling else ("ramp" if p.s < 1.0 else "rest"), progress, clock, cpu)
        falling = falling and out.kinetic > RAMP_BELOW
        if falling and out.kinetic <= QUENCH_BELOW:
            _quench(p, out)  # the fall is over: what still moves is rolling and spinning
        set_tangential_damping(p, tangential_damping_on(p, out, lay))
        if p.s < 1.0 or out.residual > lay.settle_residual:
            continue
        if out.kinetic <= lay.settle_tolerance:
            out.settled = True
            break
        _quench(p, out)  # in balance: what still moves is free motion
    out.wall_s, out.cpu_s = time.perf_counter() - clock, time.process_time() - cpu
    return p, out


def stored_arrays(p: Packing, out: Outcome) -> dict[str, np.ndarray]:
    """The run store's arrays of a ramped settling: `results.pouring.packing_arrays` (centres,
    radii, largest overlap) and what it reached: "kinetic" (kinetic energy over gravity's
    work) and "residual" (the largest residual force over a weight)."""
    from granplate.results.pouring import packing_arrays

    arrays = packing_arrays(p.x, p.radius, p.scenario.walls)
    arrays["kinetic"] = np.array(out.kinetic)
    arrays["residual"] = np.array(out.residual)
    return arrays

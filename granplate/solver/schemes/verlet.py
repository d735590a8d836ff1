"""Velocity Verlet of the granules (docs/model.md section 6.5), LAMMPS's integrator: one
evaluation of the normal forces per step, the friction at granule-granule and
granule-wall contacts split off exactly per contact, for granular runs without a plate.

One step t -> t + h (fixed h = time.dt_max, cut to land on the output times):
1. friction alone over the time it is owed, h_prev/2 + h/2 (`friction_flow`: the closing
   half step of the last step and the opening half step of this one merged, at the same
   positions), each pass in the reverse contact order of the one before;
2. kick: v += h/2 a_n; drift: x += h v (x, y, theta in the plane; x, y, z in space);
3. one force pass at t + h (`normal_forces`): the normal forces with the damping of
   eq. (3) at the predicted end velocities v + h/2 a_n (second order, where LAMMPS's
   half-step velocities are first order; solver.verlet_damping = "half_step" reads the
   half step's, as LAMMPS does), the shock on the loaded granules;
4. kick: v += h/2 a_n+1; on a step that lands on an output time, the closing friction
   half step (in the reverse order) so that the recorded state is the whole step's.

Under Mindlin's tangential law (contact.tangential_law = "mindlin", docs/model.md section
3.16) there is no split friction at those contacts: the force pass of step 3 adds each
contact's tangential spring force from the same overlap and normal force
(`mindlin_force_pass`), its history moved on by the slip at the half-step velocities (the
drift's), as LAMMPS's; its stored energy joins the contacts' and its losses (eq. M6)
D_friction. At an elastic body's contacts the same law runs after the body's force pass
(solver.body_mindlin), its slip against the surface's motion over the step.

The work of each kick is booked exactly as the kinetic energy it adds: h/2 F v_mean for
the damping part of the force (D_visc) and the load (E_shock; a line load on the elastic
body kicks its modes the same way, at t_n and t_n + h), so eq. (11)'s residual is
Verlet's own energy error, O(h^2), which the loop checks at every step. Gravity and the
drives (solver.drives) join each force pass; the drive forces' kicks are booked the same
way (gravity's too; an elastic body's own weight, a constant modal force, turns its modes
exactly about their static deflection, its work booked as gravity's), a driven wall's elastic work exactly (the change of its contacts'
energy as it moves), the damping at its velocity by the trapezoidal rule over the step
(in the drive's work and in D_visc alike), and the impulse that gives a driven granule
its prescribed velocity at t + h as the kinetic energy it adds. A force-driven wall (a
piston, solver.drives) is kicked and drifted with the granules, its force P's share of
each kick booked as the drive's work and its contacts' damping's as dissipation.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from granplate.jit import njit

from granplate.model.inputs import N_HIST_STEP, STATE_COLUMNS, BodyArrays
from granplate.physics.contact import COEF_MU
from granplate.solver import body as B
from granplate.solver.schemes import verlet_body as VB
from granplate.physics.shock import shock_amplitude
from granplate.solver.blocks import (
    N_FPAR,
    N_SPAR,
    S_DEALT,
    S_DAMPED,
    S_KE_READY,
    S_MOVED,
    S_MOVES_READY,
    S_UNDIVIDED,
    S_ZERO_ACC,
    S_ZERO_DAMP,
    S_ZERO_LOADS,
    block_count,
    copy_rows,
)
from granplate.solver.dimension import (
    friction_flow,
    kinetic_energies_part,
    mindlin_force_pass,
    normal_forces,
    normal_forces_blocks,
)
from granplate.solver.drives import (
    drive_kick_work,
    finish_pass,
    gravity_kick_work,
    hold_drives,
    piston_kick,
    piston_kick_drift,
    wall_powers,
    wall_shift_energy,
)
from granplate.solver.granular import commit_history
from granplate.solver.ladder import step_to_output
from granplate.solver.schemes.verlet_kicks import (
    N_DRIFT,
    N_NOTES,
    NOTE_KE_READY,
    NOTE_KR,
    NOTE_KX,
    NOTE_KY,
    NOTE_KZ,
    NOTE_MOVED,
    NOTE_MOVES_READY,
    closing_kick_blocks,
    closing_kick_serial,
    first_kick_blocks,
    first_kick_serial,
    kinetic_energy_blocks,
    kinetic_sums,
)

from granplate.solver.state import T_TRIAL
from granplate.solver.state import PARTNER_BODY as PARTNER_BODY

NAME = "verlet"
#: the scratch's per-granule arrays have room for the widest state (space's).
N_COLUMNS = max(STATE_COLUMNS.values())
#: columns of Scratch.split: friction time owed [s], order of the next friction pass
#: (1: forward), whether the planned step lands on an output time, whether the forces at
#: t_n are known (0 until the first step), which of the two buffers holds t_n's.
OWED, FORWARD, LAND, STARTED, CURRENT = range(5)


class Scratch(NamedTuple):
    """The Verlet scheme's own scratch: per-granule damping forces and loads at t_n and at
    the trial step's end (two buffers, swapped on commit), and the split's bookkeeping."""

    fdamp: np.ndarray  # (2, ng, N_COLUMNS) damping force on each granule [N] (velocity columns)
    fload: np.ndarray  # (2, ng, N_COLUMNS) shock load on each granule [N, N m]
    split: np.ndarray  # (5,) OWED, FORWARD, LAND, STARTED, CURRENT
    fpar: np.ndarray  # (threads, ng, N_FPAR) each thread's buffered forces on granules other blocks own [N] (solver.blocks; (0, 0, 0): serial)
    spar: np.ndarray  # (nb, N_SPAR) each block's sums (solver.blocks.block_count)
    quiet: np.ndarray  # (2, 2) per buffer: 1 where its loads (column 0), its damping forces (1) are all zero
    notes: np.ndarray  # (N_NOTES,) the serial kicks' measures (NOTE_*)


def new_scratch(ng: int, nm: int, nk: int, body: BodyArrays | None = None, threads: int = 1) -> Scratch:
    """Scratch for ng granules and nm modes (nk plate contacts: none are used; the elastic
    body in space is the loop's b, and `body` needs nothing here), and the buffers of
    blocks for `threads` threads (solver.blocks.block_count) when it is over 1."""
    split = np.zeros(5)
    split[FORWARD] = 1.0
    nb = block_count(threads)
    return Scratch(
        fdamp=np.zeros((2, ng, N_COLUMNS)),
        fload=np.zeros((2, ng, N_COLUMNS)),
        split=split,
        fpar=np.zeros((threads if nb else 0, ng if nb else 0, N_FPAR)),
        spar=np.zeros((nb, N_SPAR)),
        quiet=np.zeros((2, 2)),
        notes=np.zeros(N_NOTES),
    )


@njit(cache=True)
def plan(sw, count, cfg, pos, rem):
    """The fixed step dt_max (level 0), cut to land on the next output time `rem` [s]
    away (the remainder, or half of it when it is under two steps). Returns (level, h,
    slot, land)."""
    h, slot, land = step_to_output(0, rem, True, cfg)
    sw.split[LAND] = 1.0 if land else 0.0
    return 0, h, slot, land


@njit(cache=True)
def prepare_level(sw, h, p, slot):
    """Nothing: no plate."""
    return


@njit(cache=True)
def has_friction(g, cfg) -> bool:
    """Whether any listed pair or wall contact has a rate law's friction coefficient: none
    where the scenario gives none (cfg.rate_friction False: no mu > 0, or a history law,
    contact.tangential_law being one for every contact), and the scan of every row each
    step is then skipped."""
    if not cfg.rate_friction:
        return False
    for p in range(g.pair_coef.shape[0]):
        if g.pair_coef[p, COEF_MU] != 0.0:
            return True
    for w in range(g.wall_coef.shape[0]):
        if g.wall_coef[w, COEF_MU] != 0.0:
            return True
    return False


@njit(cache=True)
def force_pass(t, yv, yn, h, g, cfg, sw, buf, acc, commit_t, cleared=False, divide=True):
    """The force pass at (t, yn) into buffer buf (sw.fdamp[buf], sw.fload[buf]; the
    accelerations into acc): in blocks on every core when the scratch has blocks
    (solver.blocks: they leave uncleared the buffer's rows its last pass left all zero,
    sw.quiet), else serially; under Mindlin's law (cfg.history_friction) with the tangential
    springs in it, their histories moved on by the slip at yv's velocities over h [s] (0:
    the committed histories' forces); the pairs' overlaps committed at commit_t [s] (the
    trial's end as the clock will read it, st.clock[T_TRIAL]: every step is accepted; < 0:
    not, the pass at t_n); `cleared`: the first kick left acc's rows zero from the velocity
    columns on (solver.blocks.S_ZERO_ACC). The pass leaves uncleared the rows it knows zero
    (acc's where `cleared`, the buffer's where its last pass left them so: sw.quiet), in
    blocks and serially alike. Without `divide` (the normal pass alone) acc keeps the forces
    and torques, for the closing kick to divide (`closing_divides`). Returns (the ForceSums,
    the springs' stored energy [J], their losses [J]; 0 and 0 without Mindlin's law)."""
    fdamp = sw.fdamp[buf]
    fload = sw.fload[buf]
    forces, damp, loads = not cleared, sw.quiet[buf, 1] == 0.0, sw.quiet[buf, 0] == 0.0  # (which rows to clear)
    if sw.spar.shape[0] > 0:
        sw.spar[0, S_DEALT] = 1.0 if cfg.history_friction else 0.0  # (the pairs' blocks dealt out in turn)
        sw.spar[0, S_DAMPED] = 1.0  # (damped until a threaded pass in space counts its granules)
        sw.spar[0, S_ZERO_LOADS] = 0.0 if loads else 1.0
        sw.spar[0, S_ZERO_DAMP] = 0.0 if damp else 1.0
        sw.spar[0, S_ZERO_ACC] = 0.0 if forces else 1.0
        sw.spar[0, S_UNDIVIDED] = 0.0 if divide else 1.0
    if cfg.history_friction:
        return mindlin_force_pass(
            t, yv, yn, h, g, cfg, acc, fdamp, fload, sw.fpar, sw.spar, commit_t, forces, damp, loads
        )
    if sw.spar.shape[0] > 0:
        return normal_forces_blocks(t, yn, g, cfg, acc, fdamp, fload, sw.fpar, sw.spar, commit_t), 0.0, 0.0
    return normal_forces(t, yn, g, cfg, acc, fdamp, fload, commit_t, forces, damp, loads, divide), 0.0, 0.0


@njit(cache=True)
def note_quiet(sw, buf, t, b, cfg, p_visc):
    """After the force pass at t [s] into buffer buf (the elastic body's too), whose viscous
    power was p_visc [W]: whether its loads are all zero (none on the granules: the shock on
    the plate, or its amplitude 0 at t) and its damping forces (no granule given one by the
    threaded pass in space, no elastic body), in sw.quiet[buf]; the kicks then skip reading
    them (the threaded passes leave them uncleared too: solver.blocks). The threaded pass
    counted the granules it damped. The serial one damped some where its viscous power is
    not zero (each contact's damping adds its power); else its damping rows are read once
    here (`rows_zero`), where the two kicks would read them and the loads' rows."""
    sw.quiet[buf, 0] = 1.0 if cfg.load_on_plate or shock_amplitude(t, cfg) == 0.0 else 0.0
    if sw.spar.shape[0] > 0:
        undamped = sw.spar[0, S_DAMPED] == 0.0
    else:
        undamped = p_visc == 0.0 and rows_zero(sw.fdamp[buf])
    sw.quiet[buf, 1] = 1.0 if undamped and not B.has_body(b) else 0.0


@njit(cache=True)
def rows_zero(a) -> bool:
    """Whether every number of a (n, columns) from the velocity columns on (N_DRIFT) is 0."""
    for i in range(a.shape[0]):
        for c in range(N_DRIFT, a.shape[1]):
            if a[i, c] != 0.0:
                return False
    return True


@njit(cache=True)
def closing_divides(g, b, cfg) -> bool:
    """Whether the step's force pass leaves its forces undivided for the closing kick
    (solver.kicks.divide_kick: a pass over the granules fewer): where nothing reads the
    accelerations between the two (no gravity, no granule drives, no elastic body) and the
    pass applies no impulses after its division (no Mindlin's law at the walls)."""
    return not cfg.history_friction and g.gravity.shape[0] == 0 and g.drive_target.shape[0] == 0 and not B.has_body(b)


@njit(cache=True)
def start(sw, t, st, g, b, cfg):
    """The contact energies of the elastic body in space b at t = 0 (state y, modes at rest
    or as set): (the contacts' stored energy, the residual compliance's) [J]; (0, 0)
    without a body."""
    return VB.start_energies(b, st.y, int(sw.split[CURRENT]), st, g, cfg, st.k1, sw.fdamp, t)


@njit(cache=True)
def steps_in_place(sw, g) -> bool:
    """Whether the step writes its end state and derivatives into st.y and st.k1 themselves
    (every step is accepted; the loop then copies nothing): where no wall is driven, whose
    elastic work over the step reads the state at t_n beside the new one
    (solver.drives.wall_shift_energy); else into w.ynew and w.kend."""
    return g.wall_drive.shape[0] == 0


@njit(cache=True)
def start_state(y, st, b, sw, copy):
    """The trial's modes of the body b from t_n's and, where `copy` (the rate friction moves
    the velocities before the first kick, which then starts from y), y = st.y (in blocks
    when the scratch has them); else the kick starts from st.y itself, sparing the copy."""
    VB.modes_from(b, st)
    if not copy:
        return
    if sw.spar.shape[0] > 0:
        copy_rows(y, st.y)
    else:
        for i in range(y.shape[0]):
            for c in range(y.shape[1]):
                y[i, c] = st.y[i, c]


@njit(cache=True)
def first_forces(t, st, g, b, cfg, sw, cur):
    """t_n's forces, loads and damping on the run's first step (st.k1 as `initialise` has
    it; Mindlin's law with the committed histories), the body's too."""
    pr, _, _ = force_pass(t, st.y, st.y, 0.0, g, cfg, sw, cur, st.k1, -1.0)
    VB.first_forces(st.y, b, cur, st, g, cfg, st.k1, sw.fdamp)
    note_quiet(sw, cur, t, b, cfg, pr.p_visc)
    finish_pass(st.y, st.k1, g)


@njit(cache=True)
def book(w, wl, d_visc, fric, w_plastic, w_grav, w_drive, p_shock, p_visc, ovl, ovl_i, ovl_j):
    """The step's works into w.dacc (load, damping, friction, plastic, gravity, drives
    [J]), the end powers into w.pend (load, viscous [W]), the largest overlap into
    w.ovl_new / w.ovl_who."""
    w.dacc[0] = wl
    w.dacc[1] = d_visc
    w.dacc[2] = fric
    w.dacc[3] = w_plastic
    w.dacc[4] = w_grav
    w.dacc[5] = w_drive
    w.pend[0] = p_shock
    w.pend[1] = p_visc
    w.pend[2] = 0.0
    w.pend[3] = 0.0
    w.pend[4] = 0.0
    w.ovl_new[0] = ovl
    w.ovl_who[0] = ovl_i
    w.ovl_who[1] = ovl_j


@njit(cache=True)
def attempt(sw, t, h, slot, st, g, p, b, cfg, w):
    """One Verlet step from st.y into w.ynew (see the module docstring): the trial's
    accelerations at t + h into w.kend (both into st.y and st.k1 themselves where the step
    runs in place, `steps_in_place`), the load's, damping's, friction's and plastic work
    into w.dacc, the largest overlap into w.ovl_new / w.ovl_who. With an elastic body in
    space b (solver.body) its modes take the same kicks from the contact forces and turn
    exactly over h between them (into b.q, qd, committed by `commit`). Always converged, one
    force pass. Returns (True, 1, -1, stored energy at t + h [J], 0)."""
    in_place = steps_in_place(sw, g)
    threaded = sw.spar.shape[0] > 0
    if threaded:
        sw.spar[0, S_KE_READY] = 0.0
        sw.spar[0, S_MOVES_READY] = 0.0
    sw.notes[NOTE_KE_READY] = 0.0
    sw.notes[NOTE_MOVES_READY] = 0.0
    y = st.y if in_place else w.ynew
    kend = st.k1 if in_place else w.kend  # (st.k1, t_n's, is read before the force pass)
    friction = has_friction(g, cfg) or VB.body_friction(b)
    start_state(y, st, b, sw, friction and not in_place)
    y0 = y if friction else st.y  # the state the first kick starts from (it writes y)
    cur = int(sw.split[CURRENT])
    nxt = 1 - cur
    if sw.split[STARTED] == 0.0:
        first_forces(t, st, g, b, cfg, sw, cur)
    _, pd0 = wall_powers(g)  # the damping power at the driven walls' velocities at t_n
    hk = 0.5 * h
    forward = sw.split[FORWARD] != 0.0
    fric = 0.0
    if friction:
        fric = friction_flow(y, sw.split[OWED] + hk, g, cfg, forward)
        fric += VB.friction(y, b, cur, sw.split[OWED] + hk, g, cfg, forward)
    w_drive = drive_kick_work(y0, st.k1, g, hk)
    w_grav = gravity_kick_work(y0, st.k1, g, hk)
    w_piston, d_piston = piston_kick_drift(g, h)  # a force-driven wall: kicked and drifted as a granule
    predict = not cfg.half_step_damping  # the force pass at the predicted end velocities, or the half step's
    loads, damped = sw.quiet[cur, 0] == 0.0, sw.quiet[cur, 1] == 0.0  # (else all zero: not read)
    # (stepping in place, the kick clears the accelerations it reads: the pass writes over them)
    if threaded:
        wl, wd = first_kick_blocks(
            y0, y, st.k1, sw.fdamp[cur], sw.fload[cur], h, w.ytmp, sw.spar, predict, loads, damped, in_place,
            w.yref, cfg.dimension,
        )  # fmt: skip
        sw.spar[0, S_MOVES_READY] = 1.0  # (the positions move in this kick alone)
    else:
        wl, wd = first_kick_serial(
            y0, y, st.k1, sw.fdamp[cur], sw.fload[cur], h, w.ytmp, predict, loads, damped, in_place, w.yref,
            cfg.dimension, sw.notes,
        )  # fmt: skip
    wl, wd, w_grav = VB.first_kick(b, t, h, cur, cfg, wl, wd, w_grav)
    # (Mindlin: the slip over h at the half step's velocities, y's)
    divides = closing_divides(g, b, cfg)
    pr, e_t, lost_t = force_pass(t + h, y, w.ytmp, h, g, cfg, sw, nxt, kend, st.clock[T_TRIAL], in_place, not divides)
    e_pot, p_visc, w_plastic, fric, ovl, ovl_i, ovl_j = VB.end_pass(
        y, w.ytmp, st, b, cur, nxt, h, g, cfg, kend, sw.fdamp,
        pr.e_pot + e_t, pr.p_visc, pr.w_plastic, fric + lost_t, pr.ovl, pr.ovl_i, pr.ovl_j,
    )  # fmt: skip
    note_quiet(sw, nxt, t + h, b, cfg, p_visc)
    finish_pass(w.ytmp, kend, g)  # gravity and the drives
    _, pd1 = wall_powers(g)
    w_drive += drive_kick_work(y, kend, g, hk)
    w_grav += gravity_kick_work(y, kend, g, hk)
    loads, damped = sw.quiet[nxt, 0] == 0.0, sw.quiet[nxt, 1] == 0.0
    # (with the kinetic energies, where nothing moves the velocities after the kick)
    energies = g.drive_target.shape[0] == 0 and not (friction and sw.split[LAND] != 0.0)
    if threaded:
        wl2, wd2 = closing_kick_blocks(
            y, kend, sw.fdamp[nxt], sw.fload[nxt], hk, kend, N_DRIFT, sw.spar, loads, damped, g, energies, divides,
            cfg.dimension,
        )  # fmt: skip
        sw.spar[0, S_KE_READY] = 1.0 if energies else 0.0
    else:
        wl2, wd2 = closing_kick_serial(
            y, kend, sw.fdamp[nxt], sw.fload[nxt], hk, kend, loads, damped, g, energies, divides, cfg.dimension,
            sw.notes,
        )  # fmt: skip
    wp2, dp2 = piston_kick(g, hk)
    w_piston += wp2
    d_piston += dp2
    wl2, wd2 = VB.second_kick(b, t, h, nxt, cfg, wl2, wd2)
    if friction and sw.split[LAND] != 0.0:  # an output time: the closing half step
        fric += friction_flow(y, hk, g, cfg, not forward)
        fric += VB.friction(y, b, nxt, hk, g, cfg, not forward)
    # the granules' drives' impulses; the walls' elastic work (exact) and their damping's (booked in D too)
    w_drive += hold_drives(t + h, y, g) + wall_shift_energy(st.y, y, g, cfg.clip, t, t + h) + hk * (pd0 + pd1)
    w_drive += w_piston  # a piston's force P: its kicks' work (its kinetic energy is E_g's)
    d_visc = -(wd + wd2) + hk * (pd0 + pd1) + d_piston  # (a driven wall: the damping at the relative velocity)
    p_shock = pr.p_shock + VB.load_power(b, t + h, cfg)  # the body's load's power at t + h [W]
    book(w, wl + wl2, d_visc, fric, w_plastic, w_grav, w_drive, p_shock, p_visc, ovl, ovl_i, ovl_j)
    return True, 1, -1, e_pot, 0.0


@njit(cache=True)
def body_sensor_loads(sw, b, load):
    """The elastic body b's share of the sensors' readings at t_n (load (ng,) [N]): half the
    normal force of each granule's contact with it, from the force pass of t_n's buffer."""
    B.sensor_loads(b, int(sw.split[CURRENT]), load)


@njit(cache=True)
def judge(sw, t, h, slot, level, ratio, e_pot, st, g, p, b, cfg, w):
    """Every step is accepted (a fixed step). Returns (0, -1, 0, 0)."""
    return 0.0, -1, 0.0, 0.0


@njit(cache=True)
def commit(sw, t, h, slot, plate_work, fric_work, st, g, p, b, cfg, w):
    """The trial's end forces become t_n's (the buffers swap); the friction owed is half
    this step, or nothing when it landed on an output time; each friction pass made
    reverses the order of the next. Returns the plate work: 0 (no plate)."""
    VB.commit_modes(b, st, 1 - int(sw.split[CURRENT]), t + h)  # the modes and the residual's energy at t + h
    sw.split[CURRENT] = 1.0 - sw.split[CURRENT]
    sw.split[STARTED] = 1.0
    land = sw.split[LAND] != 0.0
    if not land:
        sw.split[FORWARD] = 1.0 - sw.split[FORWARD]
    sw.split[OWED] = 0.0 if land else 0.5 * h
    return 0.0


@njit(cache=True)
def commit_histories(sw, t, g, cfg):
    """The contacts' histories of the accepted step ending at t [s]: the trial's force pass
    committed the pairs' largest overlaps already (every step is accepted; `force_pass`'s
    commit_t), the walls' are committed here (solver.granular.commit_history). Pair rows
    that keep a Mindlin trial apart (N_HIST columns, as a run restarted from a result
    stored so has them) take it in here too; their overlaps, committed, stay as they are."""
    if g.pair_hist.shape[1] > N_HIST_STEP:
        commit_history(t, g.pair_hist, g.pair_coef)
    commit_history(t, g.wall_hist, g.wall_coef)
    commit_history(t, g.pc_hist, g.pc_coef)


@njit(cache=True)
def step_kinetic_energies(sw, y, g):
    """The granules' (KE_x, KE_y, KE_z, KE_rot) [J] at state y for the step's energy check:
    in blocks on every core when the scratch has blocks (`kinetic_energy_blocks`; the
    blocks' sums the step's closing kick left, where it says they are y's:
    `closing_kick_blocks`), else serially (solver.dimension.kinetic_energies)."""
    if sw.spar.shape[0] > 0:
        if sw.spar[0, S_KE_READY] != 0.0:
            sw.spar[0, S_KE_READY] = 0.0
            return kinetic_sums(sw.spar)
        return kinetic_energy_blocks(y, g, sw.spar)
    if sw.notes[NOTE_KE_READY] != 0.0:
        sw.notes[NOTE_KE_READY] = 0.0
        n = sw.notes
        return n[NOTE_KX], n[NOTE_KY], n[NOTE_KZ], n[NOTE_KR]
    return kinetic_energies_part(y, g, 0, y.shape[0], (0.0, 0.0, 0.0, 0.0))


@njit(cache=True)
def largest_move(sw) -> float:
    """The largest squared move of a granule since the contact list's reference [m^2], which
    the step's first kick measured (`first_kick_blocks` in blocks, the blocks' largest;
    `first_kick_serial`); -1 where it did not (read already): the contact watch measures."""
    if sw.spar.shape[0] == 0:
        if sw.notes[NOTE_MOVES_READY] == 0.0:
            return -1.0
        sw.notes[NOTE_MOVES_READY] = 0.0
        return sw.notes[NOTE_MOVED]
    if sw.spar[0, S_MOVES_READY] == 0.0:
        return -1.0
    sw.spar[0, S_MOVES_READY] = 0.0
    d2 = 0.0
    for k in range(sw.spar.shape[0]):
        d2 = max(d2, sw.spar[k, S_MOVED])
    return d2


@njit(cache=True)
def next_level(sw, h, slot, level, err, lam_max, rate, t_now, cfg):
    """The fixed step: (level 0, dt_max [s])."""
    return 0, cfg.dt_max


@njit(cache=True)
def contact_placed(sw, k, st, p):
    """Nothing: no plate contacts."""
    return


@njit(cache=True)
def contacts_moved(sw, t, st, p, cfg):
    """Nothing: no plate contacts."""
    return

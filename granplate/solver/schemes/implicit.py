"""The implicit coupling scheme (the default).

One step t -> t + h:
1. the plate modes are advanced exactly for interface forces linear over the step
   (Newmark above omega h = EXACT_OMEGA_H, where the exact response would alias), so the
   driving DOFs' motion at t + h/2 and t + h is affine in the unknowns U (exact_predict,
   exact_matrices); the normal forces are linear from N_n to U, the plate-contact
   friction is held at U over the step for the plate and the granule alike (backward
   Euler for the stiff friction: L-stable, no stick chatter), its work booked exactly;
2. U is found by Newton in (normal force, end slip rate) with the full Jacobian, the
   contacts coupled through the plate (schemes/newton.py);
3. the step is accepted, or redone smaller, on a local error estimate (the distance of
   the interface and granule forces from their extrapolation) and the growth of the
   energy residual (eq. 11); steps are output_interval / 2^k and tile every interval.

With an elastic body in space (solver.body, no plate contacts) steps 1-2 are the body's:
its modes advanced exactly for contact forces linear over the step, the granules' RK4
stages against its motion, the end force by a fixed point iterated to convergence
(solver.body_implicit, docs/model.md section 6.7); step 3 is the same.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from granplate.jit import njit

from granplate.model.inputs import STATE_COLUMNS, no_body
from granplate.physics.contact import contact_arm, plate_overlap
from granplate.physics.laws import keeps_history, tangential_friction
from granplate.physics.energy import energy_residual
from granplate.solver import body as B
from granplate.solver import body_implicit as BI
from granplate.solver.dimension import force_error, kinetic_energies
from granplate.solver.drives import piston_energy
from granplate.solver.rk4 import rk4_granular_step, rk4_limit
from granplate.solver.interface import forces_converged
from granplate.solver.ladder import (
    dyadic_level,
    dyadic_round,
    level_for,
    level_step,
    position_tolerance,
    realign_step,
    step_to_output,
)
from granplate.solver.plate_modal import (
    N_MCOEF,
    exact_correct,
    exact_matrices,
    exact_predict,
    modal_coefficients,
    static_matrices,
)
from granplate.solver.granular import commit_history
from granplate.solver.schemes.newton import held_friction, newton_update
from granplate.solver.state import (
    A_DRIVE,
    A_GRAVITY,
    A_FRIC,
    A_PLASTIC,
    A_SHOCK_G,
    A_SHOCK_P,
    A_VISC,
    C_LEVEL,
    E_IN_MAX,
    E_STATIC,
    E_ZERO,
    F_SCALE,
    H_LAST,
    N_LEVELS,
    RES_LAST,
)

NAME = "implicit"
#: a step whose error estimate exceeds REJECT_FACTOR * error_tol is redone smaller.
REJECT_FACTOR = 2.0
#: the step is at most the shock's duration / SHOCK_STEPS while it acts.
SHOCK_STEPS = 100
#: share of solver.energy_tol the step control lets the residual drift over a run.
ENERGY_STEP_FRACTION = 0.5
#: a jump of the residual that a smaller step does not shrink (a retry at JUMP_STEP or less
#: of the first rejected step still changing it by JUMP_KEPT or more of that step's change)
#: is the contact geometry's, not the integration's (a contact's foot crossing an element's
#: edge on an elastic solid's surface, docs/model.md section 6.7), and is accepted.
JUMP_STEP = 0.6
JUMP_KEPT = 0.8


class Scratch(NamedTuple):
    """The implicit scheme's own scratch."""

    ustar: np.ndarray  # (4, nd) known part of the driving-DOF motion (stage rows)
    jac: np.ndarray  # (nd, nd) Newton matrix
    rhs: np.ndarray  # (nd,)
    vguess: np.ndarray  # (nk,) Newton iterate of the end slip rates
    mcoef: np.ndarray  # (N_LEVELS + 1, nm, N_MCOEF) modal coefficients per level
    mmat: np.ndarray  # (N_LEVELS + 1, 4, nd, nd) driving-DOF response to the unknowns
    qn: np.ndarray  # (nm,) modes at the end of the step being tried
    qdn: np.ndarray
    bstep: BI.BodyStep  # the body's modes over the step and its fixed point (solver.body_implicit)
    chase: np.ndarray  # (3,) the first step at this t rejected by the energy term: t, |its residual change|, h


def new_scratch(ng: int, nm: int, nk: int, body=None, threads: int = 1) -> Scratch:
    """Scratch for ng granules, nm modes, nk plate contacts, and the step state of the
    model's elastic body in space `body` (None: no body; its arrays are the loop's b)."""
    nd = 2 * nk
    z = np.zeros
    b = no_body(ng, nm) if body is None else body
    return Scratch(
        ustar=z((4, nd)),
        jac=z((nd, nd)),
        rhs=z(nd),
        vguess=z(nk),
        mcoef=z((N_LEVELS + 1, nm, N_MCOEF)),
        mmat=z((N_LEVELS + 1, 4, nd, nd)),
        qn=z(nm),
        qdn=z(nm),
        bstep=BI.body_step_for(b, ng, max(STATE_COLUMNS.values())),
        chase=np.array([np.nan, 0.0, 0.0]),
    )


@njit(cache=True)
def plan(sw, count, cfg, pos, rem):
    """A dyadic level that tiles the output interval from `pos` [s] on, and its step
    (on the ladder when it lands on the output `rem` [s] away); where pos is off every
    dyadic grid down to dt_min (rounding of t after many small steps), the odd step
    back onto the level's grid. Returns (level, h, slot, land)."""
    level = dyadic_level(count[C_LEVEL], pos, cfg)
    count[C_LEVEL] = level
    h_align = realign_step(level, pos, cfg)
    if h_align > 0.0 and h_align < rem - position_tolerance(cfg):  # back onto the grid (an odd step)
        return level, h_align, N_LEVELS, False
    h, slot, land = step_to_output(level, rem, True, cfg)
    return level, h, slot, land


@njit(cache=True)
def prepare_level(sw, h, p, slot):
    """Modal coefficients and driving-DOF response matrices for a step h."""
    modal_coefficients(h, p.omega2, sw.mcoef[slot])
    exact_matrices(p.phi_d, sw.mcoef[slot], sw.mmat[slot])
    static_matrices(h, p.resid, sw.mmat[slot])


@njit(cache=True)
def stage_motion(mmat, ustar, force, stage):
    """Driving-DOF motion at t + h/2 and t + h: the known part ustar plus the response
    mmat to the unknown interface forces. Writes stage rows u(h/2), v(h/2), u(h), v(h)."""
    nd = force.shape[0]
    for r in range(4):
        for d in range(nd):
            acc = ustar[r, d]
            for e in range(nd):
                acc += mmat[r, d, e] * force[e]
            stage[r, d] = acc


@njit(cache=True)
def held_friction_target(normal, normal_new, slip_new, g, fnew):
    """The value the held plate-contact friction must take, into fnew's odd entries:
    mu Nbar tanh(k_s v_t,n+1) (eq. 5) with Nbar = (|N_n| + |N_n+1|)/2: the end slip
    rate (backward Euler) but the normal force averaged over the step, so that in gross
    slip the friction impulse is second-order accurate like the normal one."""
    for k in range(g.pc_i.shape[0]):
        if keeps_history(g.pc_coef[k]):  # a history law's end force is RK4's (not held)
            continue
        nbar = 0.5 * (normal[k] + normal_new[k])
        fnew[2 * k + 1] = tangential_friction(nbar, slip_new[k], g.pc_coef[k])


@njit(cache=True)
def attempt(sw, t, h, slot, st, g, p, b, cfg, w):
    """Known plate motion, then Newton on the interface unknowns from the guess in
    w.fguess. Returns (converged, iterations, worst contact, stored energy at t + h,
    largest slip relaxation rate of a contact whose friction RK4 integrates). With an
    elastic body in space b: `body_attempt`, else `plate_attempt`."""
    return B.by_body(
        b, body_attempt, (sw, t, h, slot, st, g, b, cfg, w), plate_attempt, (sw, t, h, slot, st, g, p, cfg, w)
    )


@njit(cache=True)
def plate_attempt(sw, t, h, slot, st, g, p, cfg, w):
    """`attempt` without an elastic body in space (the plane's plate, if any, held by
    Newton on its contacts' forces)."""
    exact_predict(t, h, st, p, cfg, sw.mcoef[slot], sw.ustar)
    for k in range(sw.vguess.shape[0]):
        sw.vguess[k] = st.slip[k]
    held_friction(st.normal, w.fguess, sw.vguess, g, w.fbar)
    converged = False
    worst = -1
    e_pot = 0.0
    rate = 0.0
    it = 0
    while it < cfg.max_iter:
        it += 1
        stage_motion(sw.mmat[slot], sw.ustar, w.fguess, w.stage)
        e_pot, rate = rk4_granular_step(t, h, w.stage, True, st, g, cfg, w)
        held_friction_target(st.normal, w.normal_new, w.slip_new, g, w.fnew)
        converged, worst = forces_converged(it, cfg.rtol, cfg.atol, w.fnew, w.fguess, w.conv_iter)
        if converged:
            break
        newton_update(h, sw.mmat[slot], w.stage[2], g, st, w, sw.jac, sw.rhs, sw.vguess)
    return converged, it, worst, e_pot, rate


@njit(cache=True)
def body_attempt(sw, t, h, slot, st, g, b, cfg, w):
    """The step with an elastic body (solver.body_implicit): the modes' end force F1
    guessed, then RK4 of the granules against the modes' motion under it and F1 relaxed
    towards the end pass's, until they agree to cfg.rtol. Returns as `attempt` (the
    worst contact -1)."""
    bs = sw.bstep
    mc = sw.mcoef[slot]
    for m in range(mc.shape[0]):
        for c in range(mc.shape[1]):
            bs.mc[m, c] = mc[m, c]
    BI.first_guess(h, st.clock[H_LAST], b, bs)
    converged = False
    e_pot = 0.0
    rate = 0.0
    it = 0
    while it < cfg.max_iter:
        it += 1
        e_pot, rate = rk4_granular_step(t, h, w.stage, True, st, g, cfg, w, b, bs)
        if BI.relax(it, cfg.rtol, b, bs):
            converged = True
            break
    return converged, it, -1, e_pot, rate


@njit(cache=True)
def held_friction_work(st, g, cfg, w):
    """Energy dissipated over the step by the held plate-contact friction [J], exactly:
    fbar times the slip displacement (dy_granule + a dtheta - du_plate,y), not a
    quadrature of fbar v_t (the plate's velocity may vibrate faster than the step)."""
    work = 0.0
    for k in range(g.pc_i.shape[0]):
        i = g.pc_i[k]
        dy = 2 * k + 1
        delta = plate_overlap(w.ynew[i, 0], g.radius[i], g.pc_x[k] + w.stage[2, 2 * k])
        arm = contact_arm(g.radius[i], max(delta, 0.0), cfg.arm_shrink)
        slide = (w.ynew[i, 1] - st.y[i, 1]) + arm * (w.ynew[i, 2] - st.y[i, 2]) - (w.stage[2, dy] - st.u[dy])
        work += w.fbar[k] * slide
    return work


@njit(cache=True)
def step_error(ratio, st, g, cfg, w):
    """Local error estimate (relative, ~ h^2 F''/2): the distance of the new interface
    forces and of the granules' net forces (m a, and I alpha / R) from their linear
    extrapolation over the last two steps, relative to the largest of these forces met
    so far and at least cfg.force_floor (so a contact's first touch is judged against
    the forces of the problem, not against itself)."""
    sc = max(st.clock[F_SCALE], cfg.force_floor)
    err = 0.0
    for d in range(w.fguess.shape[0]):
        u = w.fguess[d]
        sc = max(sc, abs(u))
        pred = st.force[d] + ratio * (st.force[d] - st.force_prev[d])
        err = max(err, abs(u - pred))
    sc, err = force_error(st.k1, st.k0, w.kend, ratio, g, sc, err)
    st.clock[F_SCALE] = sc
    if sc <= 0.0:
        return 0.0
    return err / sc


@njit(cache=True)
def judge(sw, t, h, slot, level, ratio, e_pot, st, g, p, b, cfg, w):
    """Error of the converged trial step (nothing committed yet): the local error
    estimate and the energy residual's growth (eq. 11) over its share. Returns (error
    relative to error_tol, level to retry at or -1, edge-load work [J], held-friction
    work [J])."""
    fric_work = held_friction_work(st, g, cfg, w)
    work, ep_new = B.by_body(  # the body's modes (and its line load's work), or the plate's
        b,
        BI.end_energy,
        (t, h, b, sw.bstep, cfg, sw.qn, sw.qdn),
        exact_correct,
        (t, h, st, p, cfg, sw.mcoef[slot], w.fguess, sw.qn, sw.qdn),
    )
    w.dacc[4] += B.by_body(b, BI.weight_work, (b, sw.bstep), no_weight, ())  # the body's own weight
    kx, ky, kz, kr = kinetic_energies(w.ynew, g)
    e_in = (
        st.clock[E_ZERO]
        + st.acc[A_SHOCK_G]
        + w.dacc[0]
        + st.acc[A_SHOCK_P]
        + work
        + (st.acc[A_GRAVITY] + w.dacc[4] + st.acc[A_DRIVE] + w.dacc[5])
    )
    total = (
        kx
        + ky
        + kz
        + kr
        + piston_energy(g)  # (the trial step's: 0 without pistons)
        + e_pot
        + ep_new
        + st.acc[A_VISC]
        + w.dacc[1]
        + st.acc[A_FRIC]
        + w.dacc[2]
        + fric_work
        + st.acc[A_PLASTIC]
        + w.dacc[3]
    )
    denom = max(st.clock[E_IN_MAX], e_in)
    d_res = 0.0
    if denom > 0.0 and math.isfinite(total):
        d_res = energy_residual(total, e_in, denom) - st.clock[RES_LAST]
    err = step_error(ratio, st, g, cfg, w) / cfg.error_tol
    by_energy = False
    if not (cfg.q0 != 0.0 and t < cfg.duration):  # (E_in ~ 0 while the shock starts)
        # each step may add its share of energy_tol * ENERGY_STEP_FRACTION, the run
        # (solver.energy_span: its t_end unless given) counted in steps of dt_max
        e_err = abs(d_res) * cfg.energy_span / (cfg.energy_tol * ENERGY_STEP_FRACTION * cfg.dt_max)
        if e_err > err and not jump_kept(sw.chase, t, h, d_res):
            err = e_err
            by_energy = True
    retry = -1
    if err > REJECT_FACTOR and st.clock[H_LAST] > 0.0:
        new_level = max(level_for(h * max(0.2, 0.9 / math.sqrt(err)), cfg), level + 1)
        if new_level < N_LEVELS and level_step(dyadic_round(new_level, cfg), cfg) < level_step(level, cfg):
            retry = new_level
    if retry >= 0 and by_energy and sw.chase[0] != t:
        sw.chase[0] = t
        sw.chase[1] = abs(d_res)
        sw.chase[2] = h
    return err, retry, work, fric_work


@njit(cache=True)
def jump_kept(chase, t, h, d_res) -> bool:
    """Whether the residual's change d_res over this retried step from t is a jump that the
    smaller step did not shrink (JUMP_STEP, JUMP_KEPT against the first step at t that the
    energy term rejected, `chase`), to be accepted rather than chased down to dt_min."""
    return chase[0] == t and h <= JUMP_STEP * chase[2] and abs(d_res) >= JUMP_KEPT * chase[1]


@njit(cache=True)
def commit(sw, t, h, slot, plate_work, fric_work, st, g, p, b, cfg, w):
    """Take the trial step's modes and driving-DOF motion; book the held friction's
    work; with an elastic body, its contacts' histories and the residual's energy at t + h.
    Returns the edge load's work over the step [J]."""
    w.dacc[2] += fric_work
    st.clock[E_STATIC] = B.by_body(b, BI.accept, (t, h, b, sw.bstep), no_static, (st,))
    for m in range(st.q.shape[0]):
        st.q[m] = sw.qn[m]
        st.qd[m] = sw.qdn[m]
    for d in range(st.u.shape[0]):
        st.u[d] = w.stage[2, d]
        st.v[d] = w.stage[3, d]
        st.a[d] = 0.0  # not used by the modal integration of this scheme
        st.pforce[d] = w.fguess[d]
        st.force_prev[d] = st.force[d]
        st.force[d] = w.fguess[d]
    return plate_work


@njit(cache=True)
def next_level(sw, h, slot, level, err, lam_max, rate, t_now, cfg):
    """The next step from the error estimate (grow at most 2x), RK4 stable on the
    friction it integrates (rate [1/s]: none with solver.granular_friction = "split"), the
    shock pulse resolved; below dt_min it goes on at dt_min (accuracy,
    not stability). Returns (level, step [s])."""
    h_lvl = level_step(level, cfg)
    grow = 2.0 if err <= 0.0 else min(2.0, max(0.3, 0.9 / math.sqrt(err)))
    h_new = min(max(h, h_lvl if slot == N_LEVELS else h) * grow, cfg.dt_max)
    h_new = rk4_limit(h_new, rate)
    if cfg.q0 != 0.0 and t_now < cfg.duration:
        h_new = min(h_new, cfg.duration / SHOCK_STEPS)
    new_level = dyadic_round(level_for(h_new, cfg), cfg)
    return new_level, h_new


@njit(cache=True)
def contact_placed(sw, k, st, p):
    """Nothing to derive from the modes: this scheme keeps no driving-DOF acceleration
    (st.a, zero: not used by its modal integration)."""
    st.a[2 * k] = 0.0
    st.a[2 * k + 1] = 0.0


@njit(cache=True)
def contacts_moved(sw, t, st, p, cfg):
    """Nothing: each step advances the modes from q, q' and the forces at t_n as they
    stand, with the contacts' rows of Phi_d of that step."""
    return


@njit(cache=True)
def start(sw, t, st, g, b, cfg):
    """The contacts of the elastic body in space b at t = 0 (state y, modes as set): their forces join the
    granules' derivative and viscous power (st.k1, st.p1: every step's first stage), the
    contacts start loaded at their overlaps. Returns (the contacts' stored energy, the
    residual compliance's) [J]; (0, 0) without a body."""
    return B.by_body(b, body_start, (sw, t, st, g, b, cfg), no_body_start, (sw,))


@njit(cache=True)
def no_body_start(sw):
    """`start` without an elastic body: nothing stored (0, 0) [J]."""
    return 0.0, 0.0


@njit(cache=True)
def no_weight():
    """The weight's work on an elastic body without one: 0 [J]."""
    return 0.0


@njit(cache=True)
def no_static(st):
    """The residual compliance's energy without an elastic body: st's, unchanged [J]."""
    return st.clock[E_STATIC]


@njit(cache=True)
def body_start(sw, t, st, g, b, cfg):
    """`start` with an elastic body (its docstring)."""
    bs = sw.bstep
    cur = int(bs.flags[BI.CUR])
    for m in range(st.q.shape[0]):
        bs.qs[0, m] = st.q[m]
        bs.qds[0, m] = st.qd[m]
    e_pot, pv, _, _, _, pf, _ = BI.pass_at(st.y, 0, cur, b, bs, g, cfg, st.k1, True)
    st.p1[1] += pv
    st.p1[2] += pf
    for m in range(st.q.shape[0]):
        bs.fprev[m] = b.fmodal[cur, m]
    commit_history(t, b.hist, b.coef)
    return e_pot, b.static[cur]


@njit(cache=True)
def body_sensor_loads(sw, b, load):
    """The elastic body b's share of the sensors' readings at t_n (load (ng,) [N]): half the
    normal force of each granule's contact with it, from t_n's buffer."""
    B.sensor_loads(b, int(sw.bstep.flags[BI.CUR]), load)

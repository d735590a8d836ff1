"""The paper's coupling scheme (docs/model.md section 6): granules by RK4, the plate by
Newmark (beta = 1/4, gamma = 1/2) in modal coordinates, coupled by interpolation and
fixed-point iteration on the interface forces; the step keeps the largest frictional
local-map modulus |lambda| (eq. 8) near solver.lambda_target.

One step t -> t + h:
1. predictor: the driving-DOF acceleration at t + h is affine in the interface forces,
   a_n+1 = a* + G(h) F_n+1, G(h) = Phi_d diag(1/(1 + h^2 omega^2/4)) Phi_d^T;
2. guess F_n+1, move the contact points inside the step at Newmark's constant average
   acceleration (a_n + a_n+1)/2 (the interpolation), advance the granules by RK4
   through it, recompute F_n+1; repeat until it agrees to rtol |F| + atol;
3. advance every mode with the converged forces (newmark_correct).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from granplate.jit import njit

from granplate.solver.rk4 import rk4_granular_step, rk4_limit
from granplate.solver.interface import forces_converged
from granplate.solver.ladder import level_for, level_step, step_to_output
from granplate.solver.plate_modal import modal_acceleration, newmark_correct, newmark_predict
from granplate.solver.state import C_LEVEL

NAME = "paper"


class Scratch(NamedTuple):
    """The paper scheme's own scratch."""

    astar: np.ndarray  # (nd,) known part a* of the driving-DOF acceleration at t + h
    anext: np.ndarray  # (nd,) a_n+1 = a* + G(h) F for the current guess F
    aavg: np.ndarray  # (nd,) (a_n + a_n+1)/2
    qdd_star: np.ndarray  # (nm,) known part of the modal acceleration at t + h


def new_scratch(ng: int, nm: int, nk: int, body=None, threads: int = 1) -> Scratch:
    """Scratch for ng granules, nm modes, nk plate contacts."""
    nd = 2 * nk
    return Scratch(astar=np.zeros(nd), anext=np.zeros(nd), aavg=np.zeros(nd), qdd_star=np.zeros(nm))


@njit(cache=True)
def plan(sw, count, cfg, pos, rem):
    """Level and step: the current level (count[C_LEVEL]), cut to land on the next
    output time `rem` [s] away (pos: time since the last output, unused). Returns
    (level, h, slot, land)."""
    level = count[C_LEVEL]
    h, slot, land = step_to_output(level, rem, False, cfg)
    return level, h, slot, land


@njit(cache=True)
def prepare_level(sw, h, p, slot):
    """Nothing beyond the shared G(h) and Newmark factors."""
    return


@njit(cache=True)
def interface_acceleration(gm, astar, force, anext):
    """a_n+1 = a* + G(h) F at the driving DOFs."""
    for d in range(astar.shape[0]):
        s = astar[d]
        for e in range(astar.shape[0]):
            s += gm[d, e] * force[e]
        anext[d] = s


@njit(cache=True)
def stage_motion(h, u, v, aavg, stage):
    """Driving-DOF motion at t + h/2 and t + h at the constant average acceleration
    aavg: u(s) = u_n + v_n s + aavg s^2/2, v(s) = v_n + aavg s (at s = h this is
    Newmark's update). Writes stage rows u(h/2), v(h/2), u(h), v(h)."""
    hh = 0.5 * h
    for d in range(u.shape[0]):
        stage[0, d] = u[d] + v[d] * hh + 0.5 * aavg[d] * hh * hh
        stage[1, d] = v[d] + aavg[d] * hh
        stage[2, d] = u[d] + v[d] * h + 0.5 * aavg[d] * h * h
        stage[3, d] = v[d] + aavg[d] * h


@njit(cache=True)
def attempt(sw, t, h, slot, st, g, p, b, cfg, w):
    """Predictor, then the interpolation-iteration from the guess in w.fguess.
    Returns (converged, iterations, worst contact, stored energy at t + h, largest
    slip relaxation rate of a contact whose friction RK4 integrates)."""
    newmark_predict(t, h, st, p, cfg, w.dmode[slot], sw.qdd_star, sw.astar)
    gm = w.gmat[slot]
    converged = False
    worst = -1
    e_pot = 0.0
    rate = 0.0
    it = 0
    while it < cfg.max_iter:
        it += 1
        interface_acceleration(gm, sw.astar, w.fguess, sw.anext)
        for d in range(sw.aavg.shape[0]):
            sw.aavg[d] = 0.5 * (st.a[d] + sw.anext[d])
        stage_motion(h, st.u, st.v, sw.aavg, w.stage)
        e_pot, rate = rk4_granular_step(t, h, w.stage, False, st, g, cfg, w)
        converged, worst = forces_converged(it, cfg.rtol, cfg.atol, w.fnew, w.fguess, w.conv_iter)
        if converged:
            break
        for d in range(w.fguess.shape[0]):
            w.fguess[d] = w.fnew[d]
    return converged, it, worst, e_pot, rate


@njit(cache=True)
def judge(sw, t, h, slot, level, ratio, e_pot, st, g, p, b, cfg, w):
    """A converged step is always accepted. Returns (error, retry level = -1, plate
    work = 0, friction work = 0)."""
    return 0.0, -1, 0.0, 0.0


@njit(cache=True)
def commit(sw, t, h, slot, plate_work, fric_work, st, g, p, b, cfg, w):
    """Advance every mode with the converged forces and the driving DOFs by Newmark
    (a_n+1 of the last iteration); returns the edge load's work over the step [J]."""
    work = newmark_correct(t, h, st, p, cfg, w.dmode[slot], sw.qdd_star, w.fguess)
    for d in range(st.u.shape[0]):
        a1 = sw.anext[d]
        v1 = st.v[d] + 0.5 * h * (st.a[d] + a1)
        st.u[d] = st.u[d] + h * st.v[d] + 0.25 * h * h * (st.a[d] + a1)
        st.v[d] = v1
        st.a[d] = a1
        st.pforce[d] = w.fguess[d]
        st.force_prev[d] = st.force[d]
        st.force[d] = w.fnew[d]
    return work


@njit(cache=True)
def next_level(sw, h, slot, level, err, lam_max, rate, t_now, cfg):
    """The next step keeps |lambda| near lambda_target (at most doubling) and RK4
    stable on the friction it integrates (rate [1/s]: the plate contacts', and the granule
    contacts' with solver.granular_friction = "rk4"). Returns (level, step [s])."""
    h_lvl = level_step(level, cfg)
    if lam_max > 0.0:
        h_new = min(h * cfg.lambda_target / lam_max, 2.0 * h_lvl, cfg.dt_max)
    else:
        h_new = min(2.0 * h_lvl, cfg.dt_max)
    h_new = rk4_limit(h_new, rate)
    return level_for(h_new, cfg), h_new


@njit(cache=True)
def contact_placed(sw, k, st, p):
    """Plate contact k's driving-DOF acceleration a_n = Phi_d q'' (x and y) on its rows
    of Phi_d just set, the modes held: the interpolation of the next step starts from it."""
    for c in range(2):
        row = 2 * k + c
        sa = 0.0
        for m in range(p.omega2.shape[0]):
            sa += p.phi_d[row, m] * st.qdd[m]
        st.a[row] = sa


@njit(cache=True)
def contacts_moved(sw, t, st, p, cfg):
    """After loaded patch contacts moved at t [s]: the modal acceleration q'' with the
    forces at t on the new rows of Phi_d, and a_n = Phi_d q'' at every driving DOF."""
    modal_acceleration(t, st, p, cfg, st.force)
    for d in range(p.phi_d.shape[0]):
        sa = 0.0
        for m in range(p.omega2.shape[0]):
            sa += p.phi_d[d, m] * st.qdd[m]
        st.a[d] = sa


@njit(cache=True)
def start(sw, t, st, g, b, cfg):
    """Nothing at t = 0 beyond the loop's own energies (no elastic body in space)."""
    return 0.0, 0.0

"""The elastic body's part of a velocity-Verlet step (docs/model.md sections 3.9 and 6.5):
its contact forces in each force pass (solver.body) and Mindlin's law there
(solver.body_mindlin), its modes kicked by them and by a line load, turned exactly over
the step under its own weight, the friction at its contacts split off as the granules'.

Each piece is chosen by the arrays' type when the loop compiles (`solver.body.by_body`):
a run without a body (model.inputs.NoBodyArrays) compiles none of the body's code and
gets the neutral value (nothing, zero, its sums unchanged).
"""

from __future__ import annotations

import numpy as np
from granplate.jit import njit

from granplate.physics.contact import COEF_MU
from granplate.physics.shock import shock_amplitude
from granplate.solver import body as B
from granplate.solver.body import by_body
from granplate.solver.body_mindlin import mindlin_forces as body_mindlin, step_forces as body_step_mindlin
from granplate.solver.granular import commit_history
from granplate.solver.state import E_STATIC, PARTNER_BODY


@njit(cache=True, inline="always")
def _nothing() -> None:
    return


@njit(cache=True, inline="always")
def _zero() -> float:
    return 0.0


@njit(cache=True, inline="always")
def _false() -> bool:
    return False


@njit(cache=True, inline="always")
def _zeros() -> tuple[float, float]:
    return 0.0, 0.0


@njit(cache=True, inline="always")
def _same2(a, b):
    return a, b


@njit(cache=True, inline="always")
def _same3(a, b, c):
    return a, b, c


@njit(cache=True, inline="always")
def _same7(a, b, c, d, e, f, g):
    return a, b, c, d, e, f, g


@njit(cache=True)
def body_pass(y, b, buf, q, qd, g, cfg, acc, fdamp):
    """The body's contact forces at (y, q, qd) into buffer buf (solver.body), added to the
    granules' accelerations acc and damping forces fdamp; returns (their stored energy,
    viscous power, plastic work, residual energy [J, W, J, J], largest overlap / radius,
    its granule)."""
    return B.contact_forces(y, q, qd, b, buf, g.radius, g.mass, cfg.clip, acc, fdamp[buf], True)


@njit(cache=True)
def _friction(b) -> bool:
    for i in range(b.coef.shape[0]):
        if b.coef[i, COEF_MU] != 0.0:
            return True
    return False


@njit(cache=True)
def body_friction(b) -> bool:
    """Whether any granule's contact with the body has a friction coefficient."""
    return by_body(b, _friction, (b,), _false, ())


@njit(cache=True)
def _modes_from(b, st):
    for m in range(b.q.shape[0]):
        b.q[m] = st.q[m]
        b.qd[m] = st.qd[m]


@njit(cache=True)
def modes_from(b, st):
    """The trial's modes (b.q, b.qd) from t_n's (st.q, st.qd)."""
    by_body(b, _modes_from, (b, st), _nothing, ())


@njit(cache=True)
def _first_forces(y, b, cur, st, g, cfg, acc, fdamp):
    body_pass(y, b, cur, st.q, st.qd, g, cfg, acc, fdamp)
    body_mindlin(y, st.qd, b, cur, cur, 0.0, g.radius, g.mass, g.inertia, cfg.arm_shrink, acc)


@njit(cache=True)
def first_forces(y, b, cur, st, g, cfg, acc, fdamp):
    """The body's contact forces at t_n (the run's first step) into buffer cur and acc,
    Mindlin's law with the committed histories."""
    by_body(b, _first_forces, (y, b, cur, st, g, cfg, acc, fdamp), _nothing, ())


@njit(cache=True)
def friction(y, b, buf, owed, g, cfg, forward) -> float:
    """The friction at the body's contacts alone over `owed` [s] (solver.body_friction);
    returns its dissipation [J]."""
    return by_body(
        b,
        B.friction_flow,
        (y, b.qd, owed, b, buf, g.radius, g.mass, g.inertia, cfg.arm_shrink, forward),
        _zero,
        (),
    )


@njit(cache=True)
def _first_kick(b, t, h, cur, cfg, wl, wd, w_grav):
    hk = 0.5 * h
    if cfg.load_on_plate:
        wl += B.load_kick(b.qd, b.load, shock_amplitude(t, cfg), hk)
    wd += B.kick(b.qd, b.fmodal[cur], b.fdamp[cur], hk)
    w_grav += B.turn_weighed(b.q, b.qd, b.omega, b.weight, h)  # its own weight too (model.body_weight)
    B.predicted_velocity(b, hk, cur)
    return wl, wd, w_grav


@njit(cache=True)
def first_kick(b, t, h, cur, cfg, wl, wd, w_grav):
    """The modes' opening half kick by t_n's forces (buffer cur) and load, their exact
    turn over h under their own weight, the predicted end velocities; the load's,
    damping's and weight's work [J] added to wl, wd, w_grav and returned."""
    return by_body(b, _first_kick, (b, t, h, cur, cfg, wl, wd, w_grav), _same3, (wl, wd, w_grav))


@njit(cache=True)
def _end_pass(y, ytmp, st, b, cur, nxt, h, g, cfg, acc, fdamp, e_pot, p_visc, w_plastic, fric, ovl, ovl_i, ovl_j):
    ep_b, pv_b, wp_b, _, ovl_b, i_b = body_pass(ytmp, b, nxt, b.q, b.qdp, g, cfg, acc, fdamp)
    e_bt, lost_bt = body_step_mindlin(
        y, st.q, b.q, b, cur, nxt, h, g.radius, g.mass, g.inertia, cfg.arm_shrink, acc
    )  # Mindlin's law on the body: the slip over h against the surface's motion
    if ovl_b > ovl:
        ovl, ovl_i, ovl_j = ovl_b, i_b, PARTNER_BODY
    return e_pot + (ep_b + e_bt), p_visc + pv_b, w_plastic + wp_b, fric + lost_bt, ovl, ovl_i, ovl_j


@njit(cache=True)
def end_pass(y, ytmp, st, b, cur, nxt, h, g, cfg, acc, fdamp, e_pot, p_visc, w_plastic, fric, ovl, ovl_i, ovl_j):
    """The body's force pass at t + h (the drifted state ytmp, the turned modes at their
    predicted velocities) into buffer nxt and acc, and Mindlin's law there over the step;
    its stored energy, viscous power, plastic work and Mindlin's losses added to the
    granules' (e_pot [J], p_visc [W], w_plastic [J], fric [J]) and the largest overlap
    (ovl, ovl_i, ovl_j) kept; all returned."""
    return by_body(
        b,
        _end_pass,
        (y, ytmp, st, b, cur, nxt, h, g, cfg, acc, fdamp, e_pot, p_visc, w_plastic, fric, ovl, ovl_i, ovl_j),
        _same7,
        (e_pot, p_visc, w_plastic, fric, ovl, ovl_i, ovl_j),
    )


@njit(cache=True)
def _second_kick(b, t, h, nxt, cfg, wl, wd):
    hk = 0.5 * h
    wd += B.kick(b.qd, b.fmodal[nxt], b.fdamp[nxt], hk)
    if cfg.load_on_plate:
        wl += B.load_kick(b.qd, b.load, shock_amplitude(t + h, cfg), hk)
    return wl, wd


@njit(cache=True)
def second_kick(b, t, h, nxt, cfg, wl, wd):
    """The modes' closing half kick by the end forces (buffer nxt) and load; their work
    [J] added to wl (load) and wd (damping) and returned."""
    return by_body(b, _second_kick, (b, t, h, nxt, cfg, wl, wd), _same2, (wl, wd))


@njit(cache=True)
def _load_power(b, t, cfg) -> float:
    if not cfg.load_on_plate:
        return 0.0
    return shock_amplitude(t, cfg) * np.dot(b.load, b.qd)


@njit(cache=True)
def load_power(b, t, cfg) -> float:
    """The power [W] of a line load on the body at t [s] (its modes' velocities b.qd)."""
    return by_body(b, _load_power, (b, t, cfg), _zero, ())


@njit(cache=True)
def _start(b, y, cur, st, g, cfg, acc, fdamp, t):
    e_pot, _, _, e_static, _, _ = body_pass(y, b, cur, st.q, st.qd, g, cfg, acc, fdamp)
    commit_history(t, b.hist, b.coef)  # contacts start loaded at their overlaps at t = 0
    return e_pot, e_static


@njit(cache=True)
def start_energies(b, y, cur, st, g, cfg, acc, fdamp, t):
    """The body's contact energies at t = 0 (state y, modes at rest or as set), its
    contacts' histories committed there: (the contacts' stored energy, the residual
    compliance's) [J]; (0, 0) without a body."""
    return by_body(b, _start, (b, y, cur, st, g, cfg, acc, fdamp, t), _zeros, ())


@njit(cache=True)
def _commit(b, st, nxt, t):
    for m in range(b.q.shape[0]):
        st.q[m] = b.q[m]
        st.qd[m] = b.qd[m]
    st.clock[E_STATIC] = b.static[nxt]
    commit_history(t, b.hist, b.coef)


@njit(cache=True)
def commit_modes(b, st, nxt, t):
    """The trial's modes, the residual's energy (buffer nxt) and the contacts' histories
    at t [s] become t_n's."""
    by_body(b, _commit, (b, st, nxt, t), _nothing, ())

"""One RK4 step of the granular medium with the plate's contact points moving as a scheme
prescribes (docs/model.md section 6), in either dimension: the granular derivative, its
split-off friction and energies come from solver.dimension (the plane's solver.granular
or space's solver.granular3d).
"""

from __future__ import annotations

from granplate.jit import njit

from granplate.solver import body_implicit as BI
from granplate.solver.dimension import friction_flow, granular_rhs, plate_friction_held
from granplate.solver.drives import hold_drives, piston_rk4_end, piston_stage, pistons_at_start, wall_shift_energy
from granplate.solver.mindlin_rk4 import begin_stages, next_stage, spring_rise

#: RK4 stays stable for h * rate < 2.785 on a decaying mode; the step control keeps h
#: times the friction relaxation rate of every contact that RK4 integrates below this bound.
RK4_FRICTION_LIMIT = 1.0


@njit(cache=True)
def no_granules_step(h, p1, dacc, pend, ovl_new, ovl_who):
    """rk4_granular_step without granules (a bare plate): no forces, no powers (the
    work is summed as RK4 would, from zeros), no overlap; returns (0, 0)."""
    h6 = h / 6.0
    for c in range(3):
        dacc[c] = h6 * (p1[c] + 2.0 * 0.0 + 2.0 * 0.0 + 0.0)
        pend[c] = 0.0
    dacc[3] = 0.0
    dacc[4] = 0.0
    dacc[5] = 0.0
    pend[3] = 0.0
    pend[4] = 0.0
    ovl_new[0] = 0.0
    ovl_who[0] = -1
    ovl_who[1] = -1
    return 0.0, 0.0


@njit(cache=True)
def first_stage(t, y0, hold, split, st, g, cfg, w):
    """RK4's first stage (derivative, powers) at state y0 and time t [s]: st.k1/st.p1 (the
    last step's end, first same as last), or recomputed into w.k1h/w.p1h where the held
    plate-contact friction (hold) or the split friction's half step changes it, or
    Mindlin's law needs the stage's slip (solver.mindlin_rk4). Returns whether it was
    recomputed (a flag, not the arrays: the time loop counts no references, jit.NO_REFCOUNT)."""
    if plate_friction_held(hold, g) or split or cfg.history_stages:
        pr = granular_rhs(
            t, y0, st.u, st.v, g, cfg, w.k1h, w.fscratch, w.nscratch, w.sscratch, hold, w.fbar, split, False
        )
        w.p1h[0] = pr.p_shock
        w.p1h[1] = pr.p_visc
        w.p1h[2] = pr.p_fric
        w.p1h[3] = pr.p_drive
        w.p1h[4] = pr.p_grav
        return True
    return False


@njit(cache=True)
def opening_friction(y0, h, g, cfg, w):
    """The split friction's first half step: y0 copied into w.ynew and the friction alone
    over h/2 there (`friction_flow`). Returns its dissipation [J]."""
    for i in range(y0.shape[0]):
        for c in range(y0.shape[1]):
            w.ynew[i, c] = y0[i, c]
    return friction_flow(w.ynew, 0.5 * h, g, cfg, True)


@njit(cache=True)
def drive_work(t, h, p1, p2, p3, p4, st, g, cfg, w):
    """The drives' work over the step into w.dacc[5] (RK4's quadrature of their power at
    the stages' sums p1..p4, the impulse that gives the driven granules their prescribed
    velocity at t + h, the driven walls' elastic work exactly) and gravity's into w.dacc[4]."""
    h6 = h / 6.0
    w.dacc[5] = (
        h6 * (p1[3] + 2.0 * p2.p_drive + 2.0 * p3.p_drive + p4.p_drive)
        + hold_drives(t + h, w.ynew, g)
        + wall_shift_energy(st.y, w.ynew, g, cfg.clip, t, t + h)
    )
    w.dacc[4] = h6 * (p1[4] + 2.0 * p2.p_grav + 2.0 * p3.p_grav + p4.p_grav)


@njit(cache=True)
def stage_quadrature(h6, p1, p2, p3, p4, dacc):
    """Simpson's rule of RK4 over the step (h6 = h / 6 [s]) of the shock's, the damping's
    and friction's powers at the four stages (p1: stage 1's (3,) array; p2-p4: ForceSums)
    into dacc[0:3] [J]."""
    dacc[0] = h6 * (p1[0] + 2.0 * p2.p_shock + 2.0 * p3.p_shock + p4.p_shock)
    dacc[1] = h6 * (p1[1] + 2.0 * p2.p_visc + 2.0 * p3.p_visc + p4.p_visc)
    dacc[2] = h6 * (p1[2] + 2.0 * p2.p_fric + 2.0 * p3.p_fric + p4.p_fric)


@njit(cache=True)
def record_end(pe, pend, ovl_new, ovl_who):
    """The end pass's powers at t + h (ForceSums pe) into pend, its largest overlap and
    its contact into ovl_new, ovl_who."""
    pend[0] = pe.p_shock
    pend[1] = pe.p_visc
    pend[2] = pe.p_fric
    pend[3] = pe.p_drive
    pend[4] = pe.p_grav
    ovl_new[0] = pe.ovl
    ovl_who[0] = pe.ovl_i
    ovl_who[1] = pe.ovl_j


@njit(cache=True)
def rk4_granular_step(t, h, stage, hold, st, g, cfg, w, b=None, bs=None):
    """One step of the granules from st.y with the plate's contact points at stage[0],
    stage[1] (u, v at t + h/2) and stage[2], stage[3] (u, v at t + h): RK4 of every force,
    or with cfg.split_friction, half a step of the granule-granule and granule-wall
    friction alone (`friction_flow`), RK4 of the other forces, and the other half of that
    friction in reverse order (Strang). With an elastic body in space (b: BodyArrays, bs:
    solver.body_implicit.BodyStep; None: none) its forces join every stage at the modes'
    motion in bs, its friction the split's half steps.

    Stage 1 reuses st.k1/st.p1 (first same as last), unless hold (the plate-contact
    friction held at w.fbar over the step; in the plane only, solver.dimension) or the
    split (the friction half step moves the velocities) changes it. Writes w.ynew,
    w.kend (without the split friction; with gravity and the drives, solver.drives), w.fnew
    (forces on the plate at t + h), w.normal_new, w.slip_new, w.pend (powers at t + h) and
    w.dacc (shock, viscous, friction work over the step, and the plastic work past the
    contacts' largest overlaps, whose end overlaps go into their histories' HIST_END; the
    work of gravity and of the drives), w.ovl_new and w.ovl_who (the largest relative
    overlap at t + h and its contact). Returns (stored contact energy at t + h [J], the
    largest slip relaxation rate at t + h of a contact whose friction RK4 integrates
    [1/s]: `end_rate`, and the body's Mindlin contacts' sticking rates)."""
    y0 = st.y
    ng = y0.shape[0]
    nc = y0.shape[1]
    if ng == 0:
        if b is not None:  # the body's modes over the step (no contact forces)
            BI.open_step(t, h, y0, False, st, b, bs, g, cfg, st.k1, st.p1, False)
        return no_granules_step(h, st.p1, w.dacc, w.pend, w.ovl_new, w.ovl_who)
    pistons_at_start(g)  # a piston (a force-driven wall) is one more degree of freedom of the step
    split = cfg.split_friction
    fric_split = 0.0
    if split:  # friction over [t, t + h/2]; RK4 then starts from w.ynew, updated in place
        fric_split = opening_friction(y0, h, g, cfg, w)
        y0 = w.ynew
    e_spring = begin_stages(g, cfg)
    fresh = first_stage(t, y0, hold, split, st, g, cfg, w)
    k1, p1 = (w.k1h, w.p1h) if fresh else (st.k1, st.p1)
    if b is not None:  # the body's friction half step, its forces at t_n, its modes over h
        fric_split += BI.open_step(t, h, y0, split, st, b, bs, g, cfg, k1, p1, fresh)
    hh = 0.5 * h
    piston_stage(g, 1.0, hh)
    next_stage(g, cfg, 1.0, hh, False)
    for i in range(ng):
        for c in range(nc):
            w.ytmp[i, c] = y0[i, c] + hh * k1[i, c]
    p2 = granular_rhs(
        t + hh, w.ytmp, stage[0], stage[1], g, cfg, w.k2, w.fscratch, w.nscratch, w.sscratch, hold, w.fbar, split, False
    )
    if b is not None:
        BI.stage_pass(w.ytmp, 1, b, bs, g, cfg, w.k2, 1, 2.0, hh, False)
    piston_stage(g, 2.0, hh)
    next_stage(g, cfg, 2.0, hh, False)
    for i in range(ng):
        for c in range(nc):
            w.ytmp[i, c] = y0[i, c] + hh * w.k2[i, c]
    p3 = granular_rhs(
        t + hh, w.ytmp, stage[0], stage[1], g, cfg, w.k3, w.fscratch, w.nscratch, w.sscratch, hold, w.fbar, split, False
    )
    if b is not None:
        BI.stage_pass(w.ytmp, 1, b, bs, g, cfg, w.k3, 2, 2.0, h, False)
    piston_stage(g, 2.0, h)
    next_stage(g, cfg, 2.0, h, False)
    for i in range(ng):
        for c in range(nc):
            w.ytmp[i, c] = y0[i, c] + h * w.k3[i, c]
    p4 = granular_rhs(
        t + h, w.ytmp, stage[2], stage[3], g, cfg, w.k4, w.fscratch, w.nscratch, w.sscratch, hold, w.fbar, split, False
    )
    if b is not None:
        BI.stage_pass(w.ytmp, 2, b, bs, g, cfg, w.k4, 3, 1.0, h / 6.0, True)
    h6 = h / 6.0
    piston_rk4_end(g, h)
    next_stage(g, cfg, 1.0, h6, True)
    for i in range(ng):
        for c in range(nc):  # (y0 may be w.ynew itself: each entry is read before it is written)
            w.ynew[i, c] = y0[i, c] + h6 * (k1[i, c] + 2.0 * w.k2[i, c] + 2.0 * w.k3[i, c] + w.k4[i, c])
    stage_quadrature(h6, p1, p2, p3, p4, w.dacc)
    if b is not None:  # the body's viscous and Mindlin work at the inner stages; its forces at the end
        visc, fric = BI.stage_work(h6, bs)
        w.dacc[1] += visc
        w.dacc[2] += fric
        BI.end_pass(w.ynew, b, bs, g, cfg)
    if split:  # friction over [t + h/2, t + h]
        fric_split += friction_flow(w.ynew, hh, g, cfg, False)
        if b is not None:
            fric_split += BI.close_friction(w.ynew, h, b, bs, g, cfg)
        w.dacc[2] += fric_split
    drive_work(t, h, p1, p2, p3, p4, st, g, cfg, w)
    pe = granular_rhs(
        t + h, w.ynew, stage[2], stage[3], g, cfg, w.kend, w.fnew, w.normal_new, w.slip_new, False, w.fbar, split, True
    )
    w.dacc[3] = pe.w_plastic
    w.dacc[2] -= spring_rise(g, cfg, e_spring)  # Mindlin's springs' energy is E_g's, not lost
    record_end(pe, w.pend, w.ovl_new, w.ovl_who)
    e_body = 0.0
    rate = end_rate(pe, hold, cfg)
    if b is not None:  # the end pass's body forces, energy, damping, plastic work and overlap
        e_body, rate_body, rise = BI.end_sums(b, bs, cfg, w)
        w.dacc[2] -= rise
        rate = max(rate, rate_body)
    return pe.e_pot + e_body, rate


@njit(cache=True)
def end_rate(pe, hold, cfg) -> float:
    """The largest slip relaxation rate at t + h of a contact whose friction RK4 integrates
    (ForceSums pe of the end pass) [1/s]: every contact's without the split friction, as the
    presets' results were computed; with it the plate contacts' unless held (a held
    plate-contact friction is not RK4's) and Mindlin's sticking contacts' (pe.rate)."""
    if not cfg.split_friction:
        return max(pe.rate, pe.rate_plate)
    return max(0.0 if hold else pe.rate_plate, pe.rate)


@njit(cache=True)
def rk4_limit(h, rate):
    """The step h [s], cut so that h * rate stays within RK4_FRICTION_LIMIT."""
    if rate * h > RK4_FRICTION_LIMIT:
        return RK4_FRICTION_LIMIT / rate
    return h

"""One RK4 step of the granular medium with the plate's contact points moving as a scheme
prescribes (docs/model.md section 6), in either dimension: the granular derivative, its
split-off friction and energies come from solver.dimension (the plane's solver.granular
or space's solver.granular3d).
"""

from __future__ import annotations

from numba import njit

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
    Mindlin's law needs the stage's slip (solver.mindlin_rk4)."""
    if plate_friction_held(hold, g) or split or cfg.mindlin_stages:
        pr = granular_rhs(
            t, y0, st.u, st.v, g, cfg, w.k1h, w.fscratch, w.nscratch, w.sscratch, hold, w.fbar, split, False
        )
        w.p1h[0] = pr.p_shock
        w.p1h[1] = pr.p_visc
        w.p1h[2] = pr.p_fric
        w.p1h[3] = pr.p_drive
        w.p1h[4] = pr.p_grav
        return w.k1h, w.p1h
    return st.k1, st.p1


@njit(cache=True)
def rk4_granular_step(t, h, stage, hold, st, g, cfg, w):
    """One step of the granules from st.y with the plate's contact points at stage[0],
    stage[1] (u, v at t + h/2) and stage[2], stage[3] (u, v at t + h): RK4 of every force,
    or with cfg.split_friction, half a step of the granule-granule and granule-wall
    friction alone (`friction_flow`), RK4 of the other forces, and the other half of that
    friction in reverse order (Strang).

    Stage 1 reuses st.k1/st.p1 (first same as last), unless hold (the plate-contact
    friction held at w.fbar over the step; in the plane only, solver.dimension) or the
    split (the friction half step moves the velocities) changes it. Writes w.ynew,
    w.kend (without the split friction; with gravity and the drives, solver.drives), w.fnew
    (forces on the plate at t + h), w.normal_new, w.slip_new, w.pend (powers at t + h) and
    w.dacc (shock, viscous, friction work over the step, and the plastic work past the
    contacts' largest overlaps, whose end overlaps go into their histories' HIST_END; the work of
    gravity and of the drives), w.ovl_new and w.ovl_who (the
    largest relative overlap at t + h and its contact). Returns (stored contact energy at
    t + h [J], largest slip relaxation rate at t + h of a contact whose friction RK4
    integrates [1/s]: with cfg.split_friction the plate contacts unless hold, 0 with hold;
    without it every contact, as the presets' results were computed; at least each touching
    Mindlin contact's sticking frequency, whose history the stages integrate: solver.mindlin_rk4).
    """
    y0 = st.y
    ng = y0.shape[0]
    nc = y0.shape[1]
    if ng == 0:
        return no_granules_step(h, st.p1, w.dacc, w.pend, w.ovl_new, w.ovl_who)
    pistons_at_start(g)  # a piston (a force-driven wall) is one more degree of freedom of the step
    split = cfg.split_friction
    fric_split = 0.0
    if split:  # friction over [t, t + h/2]; RK4 then starts from w.ynew, updated in place
        for i in range(ng):
            for c in range(nc):
                w.ynew[i, c] = y0[i, c]
        fric_split = friction_flow(w.ynew, 0.5 * h, g, cfg, True)
        y0 = w.ynew
    e_spring = begin_stages(g, cfg)
    k1, p1 = first_stage(t, y0, hold, split, st, g, cfg, w)
    hh = 0.5 * h
    piston_stage(g, 1.0, hh)
    next_stage(g, cfg, 1.0, hh, False)
    for i in range(ng):
        for c in range(nc):
            w.ytmp[i, c] = y0[i, c] + hh * k1[i, c]
    p2 = granular_rhs(
        t + hh, w.ytmp, stage[0], stage[1], g, cfg, w.k2, w.fscratch, w.nscratch, w.sscratch, hold, w.fbar, split, False
    )
    piston_stage(g, 2.0, hh)
    next_stage(g, cfg, 2.0, hh, False)
    for i in range(ng):
        for c in range(nc):
            w.ytmp[i, c] = y0[i, c] + hh * w.k2[i, c]
    p3 = granular_rhs(
        t + hh, w.ytmp, stage[0], stage[1], g, cfg, w.k3, w.fscratch, w.nscratch, w.sscratch, hold, w.fbar, split, False
    )
    piston_stage(g, 2.0, h)
    next_stage(g, cfg, 2.0, h, False)
    for i in range(ng):
        for c in range(nc):
            w.ytmp[i, c] = y0[i, c] + h * w.k3[i, c]
    p4 = granular_rhs(
        t + h, w.ytmp, stage[2], stage[3], g, cfg, w.k4, w.fscratch, w.nscratch, w.sscratch, hold, w.fbar, split, False
    )
    h6 = h / 6.0
    piston_rk4_end(g, h)
    next_stage(g, cfg, 1.0, h6, True)
    for i in range(ng):
        for c in range(nc):  # (y0 may be w.ynew itself: each entry is read before it is written)
            w.ynew[i, c] = y0[i, c] + h6 * (k1[i, c] + 2.0 * w.k2[i, c] + 2.0 * w.k3[i, c] + w.k4[i, c])
    w.dacc[0] = h6 * (p1[0] + 2.0 * p2.p_shock + 2.0 * p3.p_shock + p4.p_shock)
    w.dacc[1] = h6 * (p1[1] + 2.0 * p2.p_visc + 2.0 * p3.p_visc + p4.p_visc)
    w.dacc[2] = h6 * (p1[2] + 2.0 * p2.p_fric + 2.0 * p3.p_fric + p4.p_fric)
    if split:  # friction over [t + h/2, t + h]
        fric_split += friction_flow(w.ynew, hh, g, cfg, False)
        w.dacc[2] += fric_split
    # the drives' work (RK4's quadrature of their power, the impulse that gives the driven granules
    # their prescribed velocity at t + h, the driven walls' elastic work exactly) and gravity's
    w.dacc[5] = (
        h6 * (p1[3] + 2.0 * p2.p_drive + 2.0 * p3.p_drive + p4.p_drive)
        + hold_drives(t + h, w.ynew, g)
        + wall_shift_energy(st.y, w.ynew, g, cfg.clip, t, t + h)
    )
    w.dacc[4] = h6 * (p1[4] + 2.0 * p2.p_grav + 2.0 * p3.p_grav + p4.p_grav)
    pe = granular_rhs(
        t + h, w.ynew, stage[2], stage[3], g, cfg, w.kend, w.fnew, w.normal_new, w.slip_new, False, w.fbar, split, True
    )
    w.dacc[3] = pe.w_plastic
    w.dacc[2] -= spring_rise(g, cfg, e_spring)  # Mindlin's springs' energy is E_g's, not lost
    w.pend[0] = pe.p_shock
    w.pend[1] = pe.p_visc
    w.pend[2] = pe.p_fric
    w.pend[3] = pe.p_drive
    w.pend[4] = pe.p_grav
    w.ovl_new[0] = pe.ovl
    w.ovl_who[0] = pe.ovl_i
    w.ovl_who[1] = pe.ovl_j
    if not cfg.split_friction:
        return pe.e_pot, max(pe.rate, pe.rate_plate)
    # a held plate-contact friction is not RK4's; pe.rate: Mindlin's sticking contacts (else 0 here)
    return pe.e_pot, max(0.0 if hold else pe.rate_plate, pe.rate)


@njit(cache=True)
def rk4_limit(h, rate):
    """The step h [s], cut so that h * rate stays within RK4_FRICTION_LIMIT."""
    if rate * h > RK4_FRICTION_LIMIT:
        return RK4_FRICTION_LIMIT / rate
    return h

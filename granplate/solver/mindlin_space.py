"""Mindlin's tangential law in the velocity-Verlet force pass in space (docs/model.md
section 3.16): each pair's geometry and normal force, computed once by the pass's pair
loop (solver.granular3d.pair_forces with its tangential step on), serve its tangential
step too (physics.mindlin through solver.mindlin_history's per-contact step,
`mindlin_contact`); the walls' springs follow the normal pass (`wall_mindlin`). The serial
pass (`normal_mindlin_forces`) and the threaded one (solver.blocks, one block's buffer
each) run the same pair loop.
"""

from __future__ import annotations

from granplate.jit import njit

from granplate.model.inputs import HIST_MAX, HIST_RATE
from granplate.physics.contact import contact_arm
from granplate.physics.laws import keeps_history, normal_law_force, tangential_scale
from granplate.physics.space import normal_rate_3d, wall_overlap_3d
from granplate.solver.drives import begin_pass, wall_motion
from granplate.solver.clearing import clear_rows
from granplate.solver.granular import ForceSums
from granplate.solver.mindlin_history import mindlin_contact, mindlin_parted
from granplate.solver.friction_space import apply_friction_impulse
from granplate.solver.granular3d import (
    VX,
    WX,
    X,
    Y,
    Z,
    pair_forces,
    shock_loads,
    wall_forces,
    wall_slip,
)


@njit(cache=True)
def wall_mindlin(yv, yn, h, g, cfg, acc):
    """Mindlin's law at the wall contacts whose tangential law keeps a history (Mindlin's; laws.keeps_history), after the
    normal pass (a wall's few contacts: their geometry and |N| again): the slip from yv's
    velocities over h [s], |N| from yn's; the forces and torques added to the
    accelerations acc. Returns (the springs' energy [J], their losses [J])."""
    e_t = 0.0
    lost = 0.0
    for w in range(g.wall_i.shape[0]):
        c = g.wall_coef[w]
        if not keeps_history(c):
            continue
        i = g.wall_i[w]
        ri = g.radius[i]
        nx = g.wall_geo[w, 0]
        ny = g.wall_geo[w, 1]
        nz = g.wall_geo[w, 2]
        shift, vn, _ = wall_motion(g, w)
        delta = wall_overlap_3d(yn[i, X], yn[i, Y], yn[i, Z], ri, nx, ny, nz, g.wall_geo[w, 3] + shift)
        if delta <= 0.0:
            lost += mindlin_parted(g.wall_hist, w, c)
            continue
        arm = contact_arm(ri, delta, cfg.arm_shrink)
        _, vsx, vsy, vsz = wall_slip(yv, i, nx, ny, nz, arm)
        ddot = normal_rate_3d(yn[i, VX], yn[i, VX + 1], yn[i, VX + 2], nx, ny, nz) - vn
        n_abs = normal_law_force(delta, ddot, c, g.wall_hist[w, HIST_MAX], g.wall_hist[w, HIST_RATE], cfg.clip)
        a = tangential_scale(c, ri, delta)
        fx, fy, fz, e, d = mindlin_contact(g.wall_hist, w, c, a, delta, nx, ny, nz, vsx, vsy, vsz, h, n_abs)
        e_t += e
        lost += d
        apply_friction_impulse(acc, i, arm, 1.0 / g.mass[i], 1.0 / g.inertia[i], nx, ny, nz, fx, fy, fz, 1.0)
    return e_t, lost


@njit(cache=True)
def normal_mindlin_forces(t, yv, yn, h, g, cfg, acc, fdamp, fload, commit_t, forces=True, damp=True, loads=True):
    """solver.granular3d.normal_forces with Mindlin's tangential law in it (docs/model.md
    section 3.16): the shock, every listed pair and wall contact's normal force at state yn
    (its velocities the damping's) and, at the contacts whose tangential law keeps a
    history (Mindlin's; laws.keeps_history), the tangential spring's force from the same overlap and |N|, its history moved on by
    the slip at yv's velocities over h [s] (the half step's; yv's positions are yn's; h = 0:
    the force of the committed history), the trial histories as
    solver.mindlin_history.trial_column says, the pairs' overlaps committed at commit_t [s]
    (< 0: not; solver.granular.normal_forces), the rows cleared first as there. Returns (the
    ForceSums, the springs' stored energy [J], the energy they lost over the step [J])."""
    clear_rows(acc, fdamp, fload, 0, yn.shape[0], forces, damp, loads)
    begin_pass(t, g)
    p_shock = 0.0
    if not cfg.load_on_plate:
        p_shock = shock_loads(t, yn, g, cfg, acc, fload)
    p_visc, e_pot, w_plastic, ovl, ovl_i, ovl_j, e_t, lost, _, _, _, _ = pair_forces(
        yv, yn, h, g, cfg, 0, g.pair_ij.shape[0], acc, fdamp, acc, 0, yn.shape[0], True, commit_t
    )  # (every granule its own: no buffer)
    p_visc, e_pot, w_plastic, ovl, ovl_i, ovl_j = wall_forces(
        yn, g, cfg, acc, fdamp, p_visc, e_pot, w_plastic, ovl, ovl_i, ovl_j
    )
    for i in range(yn.shape[0]):
        for c in range(3):
            acc[i, VX + c] /= g.mass[i]
            acc[i, WX + c] /= g.inertia[i]
    e_w, lost_w = wall_mindlin(yv, yn, h, g, cfg, acc)
    sums = ForceSums(p_shock, p_visc, 0.0, e_pot, 0.0, ovl, ovl_i, ovl_j, 0.0, w_plastic, 0.0, 0.0)
    return sums, e_t + e_w, lost + lost_w

"""The granule-plate interface inside a step, shared by every scheme: the first guess
of the interface forces, their convergence test, criterion (8) at the contacts, and the
patch contacts that follow their granules along the face between steps.
"""
from __future__ import annotations

from numba import njit

from granplate.model.inputs import SCHEME_PAPER
from granplate.physics.contact import COEF_KS, COEF_MU, local_map_modulus, plate_overlap
from granplate.plate.face import patch_weights
from granplate.solver.granular import granular_rhs
from granplate.solver.plate_modal import modal_acceleration
from granplate.solver.state import CUSTOM_H, T_NOW


@njit(cache=True)
def first_guess(ratio, st, w):
    """Interface forces extrapolated linearly from the last two steps into w.fguess
    (ratio = h / h_last); every contact's convergence mark is cleared."""
    for d in range(w.fguess.shape[0]):
        w.fguess[d] = st.force[d] + ratio * (st.force[d] - st.force_prev[d])
    for k in range(w.conv_iter.shape[0]):
        w.conv_iter[k] = 0


@njit(cache=True)
def forces_converged(it, rtol, atol, fnew, fguess, conv_iter):
    """Whether the forces at the end of the trial step (fnew) agree with the ones the
    plate moved with (fguess) to rtol |F| + atol. Marks in conv_iter each contact still
    moving at iteration `it`; returns (converged, worst contact or -1). (Arrays, not
    the tuples: this runs every iteration.)"""
    converged = True
    worst = -1
    worst_err = 0.0
    for k in range(conv_iter.shape[0]):
        for c in range(2):
            d = 2 * k + c
            diff = abs(fnew[d] - fguess[d])
            if diff > rtol * abs(fnew[d]) + atol:
                converged = False
                conv_iter[k] = it + 1
                if diff > worst_err:
                    worst_err = diff
                    worst = k
    return converged, worst


@njit(cache=True)
def contact_modulus(k, h, gm, g, normal, slip):
    """|lambda| of eq. (8) at plate contact k for step h (gm: G(h))."""
    return local_map_modulus(g.pc_coef[k, COEF_MU], g.pc_coef[k, COEF_KS], normal[k], h,
                             gm[2 * k + 1, 2 * k + 1], slip[k])


@njit(cache=True)
def accept_contacts(h, gm, pc_coef, normal_new, slip_new, conv_iter, normal, slip, lam_int, it_int):
    """Take the end-of-step |N| and slip rates into the state (normal, slip) and keep
    the largest |lambda| (eq. 8) and iteration count per contact since the last output
    (lam_int, it_int); returns the largest |lambda| of this step. (Arrays, not the state
    tuples: this runs every step.)"""
    lam_max = 0.0
    for k in range(normal.shape[0]):
        normal[k] = normal_new[k]
        slip[k] = slip_new[k]
        lam = local_map_modulus(pc_coef[k, COEF_MU], pc_coef[k, COEF_KS], normal[k], h,
                                gm[2 * k + 1, 2 * k + 1], slip[k])
        lam_int[k] = max(lam_int[k], lam)
        it_int[k] = max(it_int[k], conv_iter[k] if conv_iter[k] > 0 else 1)
        lam_max = max(lam_max, lam)
    return lam_max


# --- patch contacts (docs/model.md section 3.5) -----------------------------------------------
#: a patch contact's weights are recomputed once its granule has moved this fraction of
#: the patch width along the face since they were last computed (any move for a zero width).
PATCH_MOVE = 1e-3


@njit(cache=True)
def place_patch(k, y_c, st, p, cfg, w):
    """Centre patch contact k at height y_c [m]: its rows of p.phi_d, w^T Phi_face (x and
    y), and its displacement, velocity and acceleration from the modes (st.u, st.v; st.a
    for the paper scheme, whose Newmark interpolation uses it)."""
    first, last = patch_weights(p.face_y, y_c, cfg.patch_width, w.wface)
    paper = cfg.scheme == SCHEME_PAPER
    for c in range(2):
        row = 2 * k + c
        su = 0.0
        sv = 0.0
        sa = 0.0
        for m in range(p.omega2.shape[0]):
            s = 0.0
            for n in range(first, last + 1):
                s += w.wface[n] * p.phi_face[2 * n + c, m]
            p.phi_d[row, m] = s
            su += s * st.q[m]
            sv += s * st.qd[m]
            sa += s * st.qdd[m]
        st.u[row] = su
        st.v[row] = sv
        st.a[row] = sa if paper else 0.0
    w.patch_y[k] = y_c


@njit(cache=True)
def move_patches(st, g, p, cfg, w):
    """After an accepted step, move every patch contact whose granule has slid along the
    face (PATCH_MOVE) and is within cfg.face_skin R of it (a patch far from its granule
    waits): new weights at the granule's height, frozen over the next step.

    The overlap stays continuous across a move: the face x the contact measures from
    (g.pc_x) takes up the change of u_c, so the stored energy of eq. (9) does not jump
    and eq. (11) stays balanced. While the contact is open that shift is released
    (back to the undeformed face, as far as it creates no overlap). A move invalidates
    the per-level matrices (they hold the contact rows) and refreshes what the next step
    starts from: the granules' derivative at t_n and, for the paper scheme, the modal
    acceleration with the forces at t_n on the new rows. Returns whether a patch moved."""
    moved = False
    for k in range(g.pc_patch.shape[0]):
        if g.pc_patch[k] == 0:
            continue
        i = g.pc_i[k]
        y_c = st.y[i, 1]
        near = plate_overlap(st.y[i, 0], g.radius[i] * (1.0 + cfg.face_skin), g.pc_x[k] + st.u[2 * k]) > 0.0
        if near and abs(y_c - w.patch_y[k]) > PATCH_MOVE * cfg.patch_width:
            u_old = st.u[2 * k]
            place_patch(k, y_c, st, p, cfg, w)
            g.pc_x[k] += u_old - st.u[2 * k]
            moved = True
        if plate_overlap(st.y[i, 0], g.radius[i], g.pc_x[k] + st.u[2 * k]) <= 0.0:
            g.pc_x[k] = cfg.plate_x0 + max(0.0, plate_overlap(st.y[i, 0], g.radius[i], cfg.plate_x0 + st.u[2 * k]))
    if moved:
        for s in range(w.g_ok.shape[0]):
            w.g_ok[s] = 0
        st.clock[CUSTOM_H] = -1.0
        pr = granular_rhs(st.clock[T_NOW], st.y, st.u, st.v, g, cfg, st.k1, w.fscratch, w.nscratch, w.sscratch,
                          False, w.fbar)
        st.p1[0] = pr[0]
        st.p1[1] = pr[1]
        st.p1[2] = pr[2]
        if cfg.scheme == SCHEME_PAPER:
            modal_acceleration(st.clock[T_NOW], st, p, cfg, st.force)
            for d in range(p.phi_d.shape[0]):
                sa = 0.0
                for m in range(p.omega2.shape[0]):
                    sa += p.phi_d[d, m] * st.qdd[m]
                st.a[d] = sa
    return moved

"""The granule-plate interface inside a step, shared by every scheme: the first guess
of the interface forces, their convergence test, criterion (8) at the contacts, and the
patch contacts that follow their granules along the face between steps.

Nothing here depends on the scheme: what a scheme derives from the contacts' rows of
Phi_d is its own (its hooks `contact_placed` and `contacts_moved`, solver/schemes),
called by the loop and the driver after these functions change the rows.
"""

from __future__ import annotations

from granplate.jit import njit

from granplate.physics.contact import local_map_modulus, plate_overlap
from granplate.physics.laws import tangential_slopes
from granplate.plate.face import patch_weights
from granplate.solver.dimension import granular_rhs
from granplate.solver.plate_modal import static_energy
from granplate.solver.state import CUSTOM_H, E_ZERO, T_NOW


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
    return local_map_modulus(tangential_slopes(normal[k], slip[k], g.pc_coef[k])[1], h, gm[2 * k + 1, 2 * k + 1])


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
        lam = local_map_modulus(tangential_slopes(normal[k], slip[k], pc_coef[k])[1], h, gm[2 * k + 1, 2 * k + 1])
        lam_int[k] = max(lam_int[k], lam)
        it_int[k] = max(it_int[k], conv_iter[k] if conv_iter[k] > 0 else 1)
        lam_max = max(lam_max, lam)
    return lam_max


# --- patch contacts (docs/model.md section 3.5) -----------------------------------------------
#: a patch contact's weights are recomputed once its granule has moved this fraction of
#: the patch width along the face since they were last computed (any move for a zero width).
PATCH_MOVE = 1e-3


@njit(cache=True)
def face_compliance(k, j, c, cj, p, w):
    """w_k^T R_face w_j for dof c of contact k and cj of contact j [m/N] (docs/model.md
    section 4.5): the truncated basis' static correction between two contacts, from
    their face weights (w.pweight, w.prange)."""
    s = 0.0
    for n in range(w.prange[k, 0], w.prange[k, 1] + 1):
        wk = w.pweight[k, n]
        if wk == 0.0:
            continue
        for m in range(w.prange[j, 0], w.prange[j, 1] + 1):
            s += wk * w.pweight[j, m] * p.resid_face[2 * n + c, 2 * m + cj]
    return s


@njit(entry=True, cache=True)
def set_face_weights(k, first, last, w):
    """Keep w.wface[first:last + 1] as contact k's face weights (w.pweight, w.prange)."""
    for n in range(w.pweight.shape[1]):
        w.pweight[k, n] = 0.0
    for n in range(first, last + 1):
        w.pweight[k, n] = w.wface[n]
    w.prange[k, 0] = first
    w.prange[k, 1] = last


@njit(cache=True)
def place_static(k, st, p, w):
    """Contact k's rows and columns of the truncated basis' residual compliance p.resid,
    w_k^T R_face w_j against every contact j (docs/model.md section 4.5). The static
    part R F of the other contacts' displacements st.u follows the change of their
    cross terms (F held)."""
    nk = p.resid.shape[0] // 2
    for j in range(nk):
        for c in range(2):
            for cj in range(2):
                val = face_compliance(k, j, c, cj, p, w)
                if j != k:
                    st.u[2 * j + cj] += (val - p.resid[2 * k + c, 2 * j + cj]) * st.force[2 * k + c]
                p.resid[2 * k + c, 2 * j + cj] = val
                p.resid[2 * j + cj, 2 * k + c] = val


@njit(cache=True)
def place_patch(k, y_c, st, p, cfg, w):
    """Centre patch contact k at height y_c [m]: its rows of p.phi_d, w^T Phi_face (x and
    y), and its displacement and velocity from the modes (st.u, st.v). With a truncated
    basis (p.resid not empty) also its static correction (place_static) and the static
    part R F of its displacement. What the scheme keeps at the rows (the paper scheme's
    acceleration st.a) is its hook `contact_placed` (loop.place_contact)."""
    first, last = patch_weights(p.face_y, y_c, cfg.patch_width, w.wface)
    truncated = p.resid_face.shape[0] > 0
    if truncated:
        set_face_weights(k, first, last, w)
        place_static(k, st, p, w)
    for c in range(2):
        row = 2 * k + c
        su = 0.0
        sv = 0.0
        for m in range(p.omega2.shape[0]):
            s = 0.0
            for n in range(first, last + 1):
                s += w.wface[n] * p.phi_face[2 * n + c, m]
            p.phi_d[row, m] = s
            su += s * st.q[m]
            sv += s * st.qd[m]
        if truncated:
            for e in range(p.resid.shape[0]):
                su += p.resid[row, e] * st.force[e]  # static part
        st.u[row] = su
        st.v[row] = sv
    w.patch_y[k] = y_c


@njit(cache=True)
def move_patches(st, g, p, cfg, w):
    """After an accepted step, move every patch contact whose granule has slid along the
    face (PATCH_MOVE) and is within cfg.face_skin R of it (a patch far from its granule
    waits): new weights at the granule's height, frozen over the next step.

    The overlap stays continuous across a move: the face x the contact measures from
    (g.pc_x) takes up the change of u_c, so the stored energy of eq. (9) does not jump
    and eq. (11) stays balanced. While the contact is open that shift is released
    (back to the undeformed face, as far as it creates no overlap). With a truncated
    basis the move also changes the static compliance R (forces held): every contact's
    face x takes up the change of its static part R F, and the change of the plate's
    static energy 1/2 F^T R F is booked as energy put in (st.clock[E_ZERO]), so that
    eq. (11) stays exact (docs/model.md section 4.5). A move invalidates
    the per-level matrices (they hold the contact rows) and refreshes the granules'
    derivative at t_n, which the next step starts from; what the scheme derives from the
    new rows with the forces at t_n (the paper scheme's modal acceleration) is its hook
    `contacts_moved`, which the loop calls when this returns True. Returns whether a
    patch moved."""
    moved = False
    truncated = p.resid_face.shape[0] > 0
    for k in range(g.pc_patch.shape[0]):
        if g.pc_patch[k] == 0:
            continue
        i = g.pc_i[k]
        y_c = st.y[i, 1]
        near = plate_overlap(st.y[i, 0], g.radius[i] * (1.0 + cfg.face_skin), g.pc_x[k] + st.u[2 * k]) > 0.0
        if near and abs(y_c - w.patch_y[k]) > PATCH_MOVE * cfg.patch_width:
            if truncated:
                e_old = static_energy(p.resid, st.force)
                for j in range(g.pc_i.shape[0]):
                    w.nscratch[j] = st.u[2 * j]
                place_patch(k, y_c, st, p, cfg, w)
                for j in range(g.pc_i.shape[0]):
                    g.pc_x[j] += w.nscratch[j] - st.u[2 * j]
                st.clock[E_ZERO] += static_energy(p.resid, st.force) - e_old
            else:
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
        pr = granular_rhs(
            st.clock[T_NOW],
            st.y,
            st.u,
            st.v,
            g,
            cfg,
            st.k1,
            w.fscratch,
            w.nscratch,
            w.sscratch,
            False,
            w.fbar,
            False,
            False,
        )
        st.p1[0] = pr.p_shock
        st.p1[1] = pr.p_visc
        st.p1[2] = pr.p_fric
        st.p1[3] = pr.p_drive
        st.p1[4] = pr.p_grav
    return moved

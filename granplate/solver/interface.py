"""The granule-plate interface inside a step, shared by every scheme: the first guess
of the interface forces, their convergence test, and criterion (8) at the contacts.
"""
from __future__ import annotations

from numba import njit

from granplate.physics.contact import COEF_KS, COEF_MU, local_map_modulus


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

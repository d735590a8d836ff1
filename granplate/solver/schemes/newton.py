"""Newton's method for the implicit scheme's interface unknowns.

The variables are, at every plate contact, the normal force's end value N and the end
slip rate v; the held friction follows as the contact's friction law at the mean normal
force (|N_n| + N)/2 and v, mu (|N_n| + N)/2 tanh(k_s v) for eq. (5) (held_friction,
physics.laws.tangential_friction), so it never leaves the friction cone and the stiff stick regime is solved in the slip
rate, where the equation is mild. Residuals: N - N(delta, rate) (eq. 2) and v - v_t
(eq. 6) after the step. The Jacobian is assembled from the contact laws' derivatives
and the plate's exact response (mmat: u, v of the driving DOFs at t + h per unit force),
so the contacts are coupled through the plate as they are physically; the granule's own
response over the step enters on the diagonal (normal force linear over the step:
h^2/(6 m), h/(2 m); held friction: h (1/m + R^2/I)).

Under a tangential law with history (Mindlin's, section 3.16) a plate contact's friction is
not held: RK4's stages integrate its spring (solver.mindlin_rk4.plate_stages) against the
plate's motion, linear in the end forces like the normal one, and its variable is the end
tangential force itself, with residual F_t - F_t(after the step) and the slope k_t times
the slip's (h^2/(6 m_t) on the granule, the plate's response through mmat) while it
sticks, mu sign(F_t) times the normal force's while it slides.
"""

from __future__ import annotations


from granplate.dense import solve_dense
from granplate.jit import njit

from granplate.model.inputs import HIST_MAX, HIST_RATE
from granplate.physics.contact import COEF_MU, plate_overlap
from granplate.physics.laws import (
    keeps_history,
    normal_law_slopes,
    tangential_friction,
    tangential_scale,
    tangential_slopes,
    tangential_stiffness,
)


#: a history law's contact whose |F_t| is within this fraction of mu |N| slides (its slope
#: in the Jacobian is the Coulomb limit's)
SLIDE_TOL = 1e-9


@njit(cache=True)
def held_friction(normal, fguess, vguess, g, fbar):
    """Held friction of each plate contact from the Newton variables, into the odd
    entries of fguess and into fbar: the contact's friction law at Nbar = (|N_n| + N_guess)/2
    and v_guess (eq. 5: mu Nbar tanh(k_s v_guess))."""
    for k in range(g.pc_i.shape[0]):
        if keeps_history(g.pc_coef[k]):  # a history law's force is its own unknown (RK4's stages)
            fbar[k] = 0.0
            continue
        nbar = 0.5 * (normal[k] + max(fguess[2 * k], 0.0))
        fguess[2 * k + 1] = tangential_friction(nbar, vguess[k], g.pc_coef[k])
        fbar[k] = fguess[2 * k + 1]


@njit(cache=True)
def history_slopes(history, delta, f_t, n_abs, radius, c):
    """A history law's (Mindlin's) slopes at a plate contact's trial end (tangential force
    on the plate f_t [N], |N| = n_abs [N], overlap delta [m]): (dF_t / d(slip) = k_t [N/m]
    while it sticks, else 0; dF_t / d|N| = mu sign(F_t) while it slides at the Coulomb
    limit, else 0). (0, 0) for a rate law or a contact out of touch."""
    if not history or delta <= 0.0:
        return 0.0, 0.0
    mu = c[COEF_MU]
    if n_abs > 0.0 and abs(f_t) >= mu * n_abs * (1.0 - SLIDE_TOL):
        return 0.0, mu if f_t > 0.0 else -mu
    return tangential_stiffness(c, tangential_scale(c, radius, delta)), 0.0


@njit(cache=True)
def law_jacobian(h, mmat, u_end, g, w, jac, rhs, vguess):
    """Residuals (rhs) and their derivatives with respect to the interface forces U
    (jac), row by row from the contact laws: dN_k/dU_e = dN/d(delta) d(delta)/dU_e +
    dN/d(rate) d(rate)/dU_e (eq. 2, or the elastic-plastic law's slope, physics.laws) and
    dv_k/dU_e (eq. 6), or under a history law dF_t/dU_e (`history_slopes`). u_end: driving-DOF
    displacement at t + h; w: the trial step's end values (ynew, fnew, slip_new)."""
    nd = jac.shape[0]
    for k in range(g.pc_i.shape[0]):
        i = g.pc_i[k]
        dx = 2 * k
        dt_ = 2 * k + 1
        c = g.pc_coef[k]
        history = keeps_history(c)
        rhs[dx] = w.fnew[dx] - w.fguess[dx]
        rhs[dt_] = w.fnew[dt_] - w.fguess[dt_] if history else w.slip_new[k] - vguess[k]
        delta = plate_overlap(w.ynew[i, 0], g.radius[i], g.pc_x[k] + u_end[dx])
        n_d = 0.0  # dN/d(delta)
        n_v = 0.0  # dN/d(delta rate)
        if delta > 0.0 and w.normal_new[k] > 0.0:
            n_d, n_v = normal_law_slopes(delta, c, g.pc_hist[k, HIST_MAX], g.pc_hist[k, HIST_RATE])
        inv_m = 1.0 / g.mass[i]
        inv_t = inv_m + g.radius[i] * g.radius[i] / g.inertia[i]
        k_t, f_n = history_slopes(history, delta, w.fnew[dt_], w.normal_new[k], g.radius[i], c)
        for e in range(nd):
            ddel = -mmat[2, dx, e]
            drate = -mmat[3, dx, e]
            dvt = -mmat[3, dt_, e]
            if e == dx:
                ddel -= h * h * inv_m / 6.0
                drate -= 0.5 * h * inv_m
            if e == dt_:
                dvt -= h * inv_t
            jac[dx, e] = n_d * ddel + n_v * drate
            jac[dt_, e] = dvt
            if history:  # d F_t / dU: k_t times the slip's, or along the Coulomb limit mu |N|'s
                dslip = -mmat[2, dt_, e] - (h * h * inv_t / 6.0 if e == dt_ else 0.0)
                jac[dt_, e] = k_t * dslip + f_n * jac[dx, e]


@njit(cache=True)
def chain_to_variables(normal, fguess, vguess, g, jac):
    """Chain rule from U to the variables z = (N, v): dU_y/dN = (df/d|N|)/2 and dU_y/dv =
    df/dv at Nbar, the friction law's slopes (physics.laws.tangential_slopes; eq. 5: mu
    tanh(k_s v)/2 and mu Nbar k_s / cosh^2(k_s v)); turns jac into d(residual)/dz."""
    nd = jac.shape[0]
    for j in range(g.pc_i.shape[0]):
        nbar = 0.5 * (normal[j] + max(fguess[2 * j], 0.0))
        f_n, phi_v = tangential_slopes(nbar, vguess[j], g.pc_coef[j])
        phi_n = 0.5 * f_n
        if keeps_history(g.pc_coef[j]):  # the variable is the force itself
            phi_n, phi_v = 0.0, 1.0
        for a in range(nd):
            dy_ = jac[a, 2 * j + 1]
            jac[a, 2 * j] = (1.0 if a == 2 * j else 0.0) - (jac[a, 2 * j] + dy_ * phi_n)
            jac[a, 2 * j + 1] = (1.0 if a == 2 * j + 1 else 0.0) - dy_ * phi_v


@njit(cache=True)
def newton_update(h, mmat, u_end, g, st, w, jac, rhs, vguess):
    """One Newton step: from the trial step's end values (w.ynew, w.fnew, w.normal_new,
    w.slip_new) and the plate response mmat, update the unknowns w.fguess (normal
    forces), vguess (slip rates) and the held friction (w.fguess odd entries, w.fbar)."""
    law_jacobian(h, mmat, u_end, g, w, jac, rhs, vguess)
    chain_to_variables(st.normal, w.fguess, vguess, g, jac)
    solve_dense(jac, rhs)
    for k in range(g.pc_i.shape[0]):
        w.fguess[2 * k] += rhs[2 * k]
        if keeps_history(g.pc_coef[k]):
            w.fguess[2 * k + 1] += rhs[2 * k + 1]
        else:
            vguess[k] += rhs[2 * k + 1]
    held_friction(st.normal, w.fguess, vguess, g, w.fbar)
